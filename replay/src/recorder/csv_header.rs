//! A CSV recording's header: the rate comment and the column names, as `csv::write` writes
//! them.

use std::fmt::Write as _;

/// Appends the header of a CSV take of `labels` at `rate_hz` to `text`, with a `timecode`
/// column when `timecode`.
pub(super) fn csv_header(text: &mut String, labels: &[String], rate_hz: f64, timecode: bool) {
    writeln!(text, "# rate_hz={rate_hz} units=mm").expect("String write");
    text.push_str("frame,time");
    if timecode {
        text.push_str(",timecode");
    }
    for label in labels {
        for axis in ["x", "y", "z"] {
            write!(text, ",{label}_{axis}").expect("String write");
        }
    }
    text.push('\n');
}
