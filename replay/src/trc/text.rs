//! Line and cell primitives shared by the two text formats (TRC here, CSV in `crate::csv`).
//!
//! They live under `trc` only because a module of the text formats' own would sit outside the
//! paths these readers own; nothing here is TRC specific.

use std::io::{BufRead, Read};

use crate::error::{ReadError, WriteError};

/// The longest text line read, MiB: a row of 100,000 markers is about 4 MiB. A longer line (a
/// binary file, or text without newlines) is an error, not a buffer that grows with the file.
const MAX_LINE_MIB: u64 = 16;

/// Reads a text file line by line, numbering lines from 1 and stripping `\n` or `\r\n`.
///
/// Lines are read as bytes and checked for UTF-8 here, so a bad byte is reported with its line
/// number instead of as an anonymous I/O error.
#[derive(Debug)]
pub(crate) struct Lines<R> {
    input: R,
    text: String,
    number: usize,
    /// Whether the last line read ended in `\n` (a cut-off file's last line does not).
    terminated: bool,
}

impl<R: BufRead> Lines<R> {
    /// Wraps a buffered reader positioned at the start of the file.
    pub(crate) fn new(input: R) -> Self {
        Lines {
            input,
            text: String::new(),
            number: 0,
            terminated: true,
        }
    }

    /// Number of the next line [`Lines::next_line`] would return.
    pub(crate) fn next_number(&self) -> usize {
        self.number + 1
    }

    /// The next line with its 1-based number, or `None` at the end of input.
    ///
    /// # Errors
    /// I/O failure or a line that is not UTF-8.
    pub(crate) fn next_line(&mut self) -> Result<Option<(usize, &str)>, ReadError> {
        // Reuse the previous line's allocation for the raw bytes.
        let mut bytes = std::mem::take(&mut self.text).into_bytes();
        bytes.clear();
        let most = MAX_LINE_MIB << 20;
        if (&mut self.input)
            .take(most + 1)
            .read_until(b'\n', &mut bytes)?
            == 0
        {
            return Ok(None);
        }
        self.number += 1;
        if bytes.len() as u64 > most {
            return Err(ReadError::LineTooLong {
                line: self.number,
                max_mib: MAX_LINE_MIB,
            });
        }
        self.terminated = bytes.last() == Some(&b'\n');
        if self.terminated {
            bytes.pop();
        }
        if bytes.last() == Some(&b'\r') {
            bytes.pop();
        }
        self.text =
            String::from_utf8(bytes).map_err(|_| ReadError::NotUtf8 { line: self.number })?;
        // Spreadsheet and Windows exporters often start files with a UTF-8 byte order mark.
        if self.number == 1 && self.text.starts_with('\u{feff}') {
            self.text.drain(..'\u{feff}'.len_utf8());
        }
        Ok(Some((self.number, &self.text)))
    }

    /// Whether the last line returned ended in a newline. Only the last line of a file can lack
    /// one; with a short row, that is the mark of a file cut off mid-write.
    pub(crate) fn terminated(&self) -> bool {
        self.terminated
    }

    /// The next line that holds anything but whitespace, or `None` at the end of input.
    ///
    /// # Errors
    /// As [`Lines::next_line`].
    pub(crate) fn next_non_blank(&mut self) -> Result<Option<(usize, &str)>, ReadError> {
        loop {
            // Two lookups because returning the borrow from inside the loop would keep `self`
            // borrowed across iterations.
            match self.next_line()? {
                None => return Ok(None),
                Some((_, line)) if line.trim().is_empty() => continue,
                Some(_) => return Ok(Some((self.number, &self.text))),
            }
        }
    }
}

impl<R: BufRead> Lines<R> {
    /// The next non-blank line ended by a newline; `None` at the end of input, and at a last
    /// line without one (a row cut off mid-write).
    ///
    /// # Errors
    /// As [`Lines::next_line`].
    pub(crate) fn next_whole(&mut self) -> Result<Option<(usize, &str)>, ReadError> {
        let found = self.next_non_blank()?.is_some();
        Ok((found && self.terminated).then_some((self.number, &self.text)))
    }
}

/// What a sample cell may hold.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Sample {
    /// Empty or `NaN`: the marker is missing in this frame.
    Missing,
    /// A finite number, in the file's units.
    Value(f64),
}

/// What a sample cell must hold, for error messages.
pub(crate) const EXPECTED_SAMPLE: &str = "a finite number, an empty cell or NaN";

/// Parses a sample cell: blank and `NaN` (any case) mean missing; anything else must be a finite
/// number. Surrounding spaces are ignored.
///
/// # Errors
/// The text to report for a non-numeric or infinite cell (the caller knows line and column).
pub(crate) fn parse_sample(cell: &str) -> Result<Sample, &'static str> {
    let cell = trim(cell);
    if cell.is_empty() {
        return Ok(Sample::Missing);
    }
    match crate::decimal::parse_plain(cell).map_or_else(|| cell.parse::<f64>(), Ok) {
        Ok(v) if v.is_nan() => Ok(Sample::Missing),
        Ok(v) if v.is_finite() => Ok(Sample::Value(v)),
        _ => Err(EXPECTED_SAMPLE),
    }
}

/// `cell.trim()`, in the common case (ASCII at both ends once ASCII whitespace is gone) without
/// decoding characters: `str::trim` also removes Unicode whitespace (U+000B and U+00A0 among
/// them), so any other end takes std's path.
fn trim(cell: &str) -> &str {
    let t = cell.trim_ascii();
    let plain = |b: Option<&u8>| b.is_none_or(|&b| b.is_ascii() && b != 0x0b);
    if plain(t.as_bytes().first()) && plain(t.as_bytes().last()) {
        t
    } else {
        cell.trim()
    }
}

/// The cells of a row separated by `sep` (an ASCII byte), as `row.split(sep)` gives them, in
/// one SIMD pass over the row: std's `split` sets out afresh for each separator, which took as
/// long as parsing the numbers. `width` is the number of cells expected: room is reserved for
/// it, but never for more cells than the row can hold (a header naming a million markers does
/// not make each short row allocate for a million).
pub(crate) fn split_cells(row: &str, sep: u8, width: usize) -> Vec<&str> {
    debug_assert!(
        sep.is_ascii(),
        "a separator inside a character would split it"
    );
    let mut cells = Vec::with_capacity(width.min(row.len() + 1));
    let mut start = 0;
    for end in memchr::memchr_iter(sep, row.as_bytes()) {
        cells.push(&row[start..end]);
        start = end + 1;
    }
    cells.push(&row[start..]);
    cells
}

/// Parses a frame number: an integer, or a number with no fractional part (`12.0`), which some
/// exporters write.
pub(crate) fn parse_frame_number(cell: &str) -> Option<i64> {
    let cell = cell.trim();
    if let Ok(n) = cell.parse::<i64>() {
        return Some(n);
    }
    let v = cell.parse::<f64>().ok()?;
    // The bounds keep the cast exact; frame numbers this large are not real data.
    (v.fract() == 0.0 && v.abs() < 9.0e15).then_some(v as i64)
}

/// Parses a time cell: a finite number of seconds.
pub(crate) fn parse_time(cell: &str) -> Option<f64> {
    cell.trim().parse::<f64>().ok().filter(|t| t.is_finite())
}

/// Checks that a row's frame number follows the previous one, and returns it.
///
/// # Errors
/// [`ReadError::BadCell`] for a non-integer, [`ReadError::FrameGap`] for a skipped or repeated
/// frame. Gaps are errors rather than filled with missing samples because a hole in the numbering
/// usually means a damaged or hand-edited file, and the take's time axis is the row order.
pub(crate) fn check_frame_number(
    cell: &str,
    line: usize,
    expected: Option<i64>,
    field: &str,
) -> Result<i64, ReadError> {
    let found = parse_frame_number(cell).ok_or_else(|| ReadError::BadCell {
        line,
        column: 1,
        field: field.to_owned(),
        expected: "an integer frame number",
        found: cell.to_owned(),
    })?;
    match expected {
        Some(expected) if expected != found => Err(ReadError::FrameGap {
            line,
            expected,
            found,
        }),
        _ => Ok(found),
    }
}

/// Parses a row's sample cells into `xyz` (mm) and `gone` (one flag per marker). `cells` may be
/// shorter than `xyz`: absent cells mean missing. `first_column` is the 0-based column of
/// `cells[0]` in the row, for error messages.
///
/// # Errors
/// [`ReadError::BadCell`] naming line, column and `<label> <axis>` for text, infinity, or a value
/// that overflows `f32` once scaled to millimetres.
pub(crate) fn parse_samples(
    line: usize,
    cells: &[&str],
    first_column: usize,
    labels: &[String],
    scale_to_mm: f64,
    xyz: &mut [f32],
    gone: &mut [bool],
) -> Result<(), ReadError> {
    gone.fill(false);
    for (i, value) in xyz.iter_mut().enumerate() {
        let cell = cells.get(i).copied().unwrap_or("");
        let field = || format!("{} {}", labels[i / 3], ["x", "y", "z"][i % 3]);
        match parse_sample(cell) {
            Ok(Sample::Missing) => {
                gone[i / 3] = true;
                *value = 0.0;
            }
            Ok(Sample::Value(v)) => {
                *value = (v * scale_to_mm) as f32;
                if !value.is_finite() {
                    let expected = "a coordinate within f32 range";
                    return Err(bad_cell(line, first_column + i, &field(), expected, cell));
                }
            }
            Err(expected) => {
                return Err(bad_cell(line, first_column + i, &field(), expected, cell));
            }
        }
    }
    Ok(())
}

/// A [`ReadError::BadCell`] from a 0-based `column`.
pub(crate) fn bad_cell(
    line: usize,
    column: usize,
    field: &str,
    expected: &'static str,
    found: &str,
) -> ReadError {
    ReadError::BadCell {
        line,
        column: column + 1,
        field: field.to_owned(),
        expected,
        found: found.to_owned(),
    }
}

/// Formats a sample cell for writing: the shortest text that reads back to the same `f32`, so
/// round trips are exact and files stay compact (std's `{}`, written faster).
pub(crate) fn push_sample(out: &mut String, value: f32) {
    crate::decimal::push_f32(out, value);
}

/// Rejects labels holding a character the format uses as a separator, before anything is
/// written, so a bad take never leaves half a file behind.
///
/// # Errors
/// [`WriteError::LabelUnrepresentable`] naming the first offending label and character.
pub(crate) fn check_labels(
    labels: &[String],
    format: &'static str,
    forbidden: &[char],
) -> Result<(), WriteError> {
    for label in labels {
        if let Some(c) = label.chars().find(|c| forbidden.contains(c)) {
            return Err(WriteError::LabelUnrepresentable {
                format,
                label: label.clone(),
                forbidden: c,
            });
        }
    }
    Ok(())
}

/// Formats frame index `f` of `take` as one row — frame `number`, `time` (seconds from the
/// take's first frame), then x y z per marker, empty cells for a missing sample — separated by
/// `sep` and ending in a newline. The caller numbers the row so a take written in blocks gets
/// the numbers and times the whole take would.
pub(crate) fn write_row(
    line: &mut String,
    take: &crate::Take,
    f: usize,
    (number, time): (i64, f64),
    sep: char,
) {
    use std::fmt::Write as _;
    write!(line, "{number}{sep}{time:.6}").expect("writing to a String cannot fail");
    for m in 0..take.n_markers() {
        match take.sample(f, m) {
            Some(p) => {
                for v in p {
                    line.push(sep);
                    push_sample(line, v);
                }
            }
            None => {
                for _ in 0..3 {
                    line.push(sep);
                }
            }
        }
    }
    line.push('\n');
}

/// Writes every frame of `take` as rows numbered from frame index `index` of a take that
/// starts at frame `first_frame`, reusing `line`.
///
/// # Errors
/// I/O failure.
pub(crate) fn write_rows(
    out: &mut impl std::io::Write,
    take: &crate::Take,
    (first_frame, index): (i64, usize),
    sep: char,
    line: &mut String,
) -> std::io::Result<()> {
    for f in 0..take.n_frames() {
        let i = index + f;
        line.clear();
        let at = (first_frame.wrapping_add(i as i64), i as f64 / take.rate_hz);
        write_row(line, take, f, at, sep);
        out.write_all(line.as_bytes())?;
    }
    Ok(())
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // a failed unwrap is a failed test
mod tests;
