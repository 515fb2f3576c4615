//! CSV takes: one row per frame, three columns per marker.
//!
//! ```text
//! # rate_hz=120 units=mm
//! frame,time,Lip_Upper_x,Lip_Upper_y,Lip_Upper_z,Chin_x,Chin_y,Chin_z
//! 1,0.000000,12.5,-3.25,40,,,
//! 2,0.008333,12.75,-3.5,40.25,1,2,3
//! ```
//!
//! Reading rules (every violation is a typed [`ReadError`] naming the line, and the column and
//! marker where there is one; nothing panics on bad input):
//! - Leading lines starting with `#` are comments; in them `rate_hz=<Hz>` and `units=<mm|cm|m>`
//!   are read and any other text is ignored. Values are converted to millimetres and the declared
//!   units (default mm) kept in [`Take::source_units`].
//! - The header is `frame,time` then `<label>_x,<label>_y,<label>_z` per marker. Labels may
//!   contain underscores (each column splits at its last `_`) and spaces; header cells are trimmed
//!   and may be double-quoted. Labels cannot contain commas.
//! - Every data row has exactly the header's column count ([`ReadError::ColumnCount`]); blank
//!   lines and CRLF are tolerated.
//! - A last line without its newline is a row cut off mid-write (a recording killed, a power
//!   cut): the take ends before it, whatever it holds, since a row cut inside its last number
//!   would otherwise read as a wrong value. emoshift writes every row whole, newline included;
//!   a file of another program that lacks its final newline loses its last row here, and
//!   [`crate::repair::inspect`] (`emoshift info`) says so. An empty or `NaN` cell means missing, and a marker is missing in
//!   a frame if any of its three cells is; `inf` or text is [`ReadError::BadCell`].
//! - The first row's `frame` is the take's first frame; later rows must count up by one
//!   ([`ReadError::FrameGap`]).
//! - Rate: `rate_hz` from the comment when present (the time column is then only checked to be
//!   numeric). Otherwise it is derived from the time column: the mean step over the take, snapped
//!   to the simplest rate the column's decimal precision allows (an integer, an NTSC x/1.001 rate,
//!   or the fewest decimals); see `rate::derive_rate`. Fewer than two frames without `rate_hz` is
//!   [`ReadError::NoRate`]; a non-increasing or irregular time column is
//!   [`ReadError::UnevenTime`].
//!
//! Writing emits `# rate_hz=<exact rate> units=mm` (so single-frame takes keep their rate), times
//! to the microsecond, the shortest decimal text that reads back to the same `f32` (round trips are
//! exact), and empty cells for missing samples.

mod header;
mod rate;
mod rows;

use std::io::{BufReader, Read, Write};

pub use self::rows::CsvBlocks;
use crate::error::{ReadError, WriteError};
use crate::trc::text;
use crate::Take;

/// Reads a CSV take (values converted to millimetres): the block reader run to the end.
///
/// # Errors
/// I/O failure, malformed content (see the module docs for each rule), unknown units, no
/// derivable rate, or a take that breaks a [`Take`] invariant (no markers, duplicate labels).
pub fn read(input: impl Read) -> Result<Take, ReadError> {
    let mut blocks = CsvBlocks::new(BufReader::new(input))?;
    let mut take = blocks.header().empty_take();
    blocks.read_block(usize::MAX, &mut take)?;
    take.rate_hz = blocks.rate_hz()?;
    take.validate()?;
    Ok(take)
}

/// Writes a CSV take in millimetres, with a `# rate_hz=... units=mm` comment line first.
///
/// # Errors
/// A take that breaks a [`Take`] invariant, a label holding a comma, double quote or line break
/// ([`WriteError::LabelUnrepresentable`]), or I/O failure. Nothing is written when the take or a
/// label is rejected.
pub fn write(take: &Take, out: &mut impl Write) -> Result<(), WriteError> {
    take.validate()?;
    check_labels(&take.labels)?;
    write_header(out, &take.labels, take.rate_hz)?;
    text::write_rows(out, take, (take.first_frame, 0), ',', &mut String::new())?;
    Ok(())
}

/// Rejects labels CSV cannot hold (a comma, a double quote, a line break).
pub(crate) fn check_labels(labels: &[String]) -> Result<(), WriteError> {
    text::check_labels(labels, "csv", &[',', '"', '\n', '\r'])
}

/// The rate comment and the column header.
pub(crate) fn write_header(
    out: &mut impl Write,
    labels: &[String],
    rate_hz: f64,
) -> std::io::Result<()> {
    writeln!(out, "# rate_hz={rate_hz} units=mm")?;
    let mut line = String::from("frame,time");
    for label in labels {
        for axis in ["x", "y", "z"] {
            line.push(',');
            line.push_str(label);
            line.push('_');
            line.push_str(axis);
        }
    }
    writeln!(out, "{line}")
}
