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
//!   lines and CRLF are tolerated. An empty or `NaN` cell means missing, and a marker is missing in
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

use std::io::{BufReader, Read, Write};

use self::header::{parse_comment, parse_header, Meta};
use crate::error::{ReadError, WriteError};
use crate::trc::text::{self, check_frame_number, parse_time, Lines};
use crate::{Take, Units};

/// Reads a CSV take (values converted to millimetres).
///
/// # Errors
/// I/O failure, malformed content (see the module docs for each rule), unknown units, no
/// derivable rate, or a take that breaks a [`Take`] invariant (no markers, duplicate labels).
pub fn read(input: impl Read) -> Result<Take, ReadError> {
    let mut lines = Lines::new(BufReader::new(input));
    let mut meta = Meta::default();
    let (labels, extra) = loop {
        let line = lines.next_number();
        match lines.next_non_blank()? {
            Some((n, text)) if text.trim_start().starts_with('#') => {
                parse_comment(n, text, &mut meta)?;
            }
            Some((n, text)) => break parse_header(n, text)?,
            None => {
                let expected = "the `frame,time,<label>_x,<label>_y,<label>_z,...` header";
                return Err(ReadError::UnexpectedEnd { line, expected });
            }
        }
    };
    let units = meta.units.unwrap_or(Units::Millimetres);
    let mut take = Take::new(labels, meta.rate_hz.unwrap_or(1.0), 1);
    take.source_units = units;
    let rows = read_rows(&mut lines, &mut take, meta.rate_hz.is_none(), extra)?;
    if let Some(first) = rows.first_frame {
        take.first_frame = first;
    }
    if meta.rate_hz.is_none() {
        take.rate_hz = rate::derive_rate(&rows.times, rows.resolution_s)?;
    }
    take.validate()?;
    Ok(take)
}

/// What the data rows tell beyond the samples.
struct Rows {
    first_frame: Option<i64>,
    /// `(line, time_s)` per row, collected only when the rate must be derived.
    times: Vec<(usize, f64)>,
    /// The time column's last decimal place, seconds (0 when written with exponents).
    resolution_s: f64,
}

/// Reads every data row into `take` (whose labels and units are set).
fn read_rows<R: std::io::BufRead>(
    lines: &mut Lines<R>,
    take: &mut Take,
    keep_times: bool,
    extra: usize,
) -> Result<Rows, ReadError> {
    let n = take.n_markers();
    let width = 2 + extra + 3 * n;
    let scale = f64::from(take.source_units.to_mm());
    let (mut xyz, mut gone) = (vec![0.0f32; 3 * n], vec![false; n]);
    let mut rows = Rows {
        first_frame: None,
        times: Vec::new(),
        resolution_s: 1.0,
    };
    let mut max_decimals = Some(0u32);
    let mut next_frame = None;
    while let Some((line, row)) = lines.next_non_blank()? {
        let cells: Vec<&str> = row.split(',').collect();
        if cells.len() != width {
            let found = cells.len();
            return Err(ReadError::ColumnCount {
                line,
                expected: width,
                found,
            });
        }
        let frame = check_frame_number(cells[0], line, next_frame, "frame")?;
        rows.first_frame.get_or_insert(frame);
        next_frame = Some(frame.wrapping_add(1));
        let time_s = parse_time(cells[1])
            .ok_or_else(|| text::bad_cell(line, 1, "time", "a time in seconds", cells[1]))?;
        if keep_times {
            rows.times.push((line, time_s));
            max_decimals = max_decimals
                .zip(rate::decimals(cells[1]))
                .map(|(a, b)| a.max(b));
        }
        text::parse_samples(
            line,
            &cells[2 + extra..],
            2 + extra,
            &take.labels,
            scale,
            &mut xyz,
            &mut gone,
        )?;
        take.push_frame(&xyz, &gone);
    }
    rows.resolution_s = max_decimals.map_or(0.0, |d| 10f64.powi(-(d.min(300) as i32)));
    Ok(rows)
}

/// Writes a CSV take in millimetres, with a `# rate_hz=... units=mm` comment line first.
///
/// # Errors
/// A take that breaks a [`Take`] invariant, a label holding a comma, double quote or line break
/// ([`WriteError::LabelUnrepresentable`]), or I/O failure. Nothing is written when the take or a
/// label is rejected.
pub fn write(take: &Take, out: &mut impl Write) -> Result<(), WriteError> {
    take.validate()?;
    text::check_labels(&take.labels, "csv", &[',', '"', '\n', '\r'])?;
    writeln!(out, "# rate_hz={} units=mm", take.rate_hz)?;
    let mut line = String::from("frame,time");
    for label in &take.labels {
        for axis in ["x", "y", "z"] {
            line.push(',');
            line.push_str(label);
            line.push('_');
            line.push_str(axis);
        }
    }
    writeln!(out, "{line}")?;
    for f in 0..take.n_frames() {
        line.clear();
        text::write_row(&mut line, take, f, ',');
        out.write_all(line.as_bytes())?;
    }
    Ok(())
}
