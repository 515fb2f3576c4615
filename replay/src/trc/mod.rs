//! TRC takes: the tab-separated OpenSim / Motion Analysis layout.
//!
//! ```text
//! PathFileType  4  (X/Y/Z)  take.trc
//! DataRate  CameraRate  NumFrames  NumMarkers  Units  OrigDataRate  OrigDataStartFrame  OrigNumFrames
//! 60.00     60.00       962        41          mm     60.00         1                   962
//! Frame#  Time  ForeHead_M  <empty>  <empty>  ForeHead_L  <empty>  <empty> ...
//!               X1          Y1       Z1       X2          Y2       Z2 ...
//! <blank line, optional>
//! 1       0.000000  143.5201  842.2137  29.0542  185.6148 ...
//! ```
//!
//! Reading rules (every violation is a typed [`ReadError`] naming the line, and the column and
//! marker where there is one; nothing panics on bad input):
//! - Cells are separated by single tabs; CRLF line ends, blank lines and trailing empty cells are
//!   tolerated.
//! - `Units` `mm`, `cm` or `m`; values are converted to millimetres and the declared units kept in
//!   [`Take::source_units`]. Other units are [`ReadError::UnknownUnits`].
//! - A blank or `NaN` cell means missing; a marker is missing in a frame if any of its three cells
//!   is. `inf` or text is [`ReadError::BadCell`].
//! - A row shorter than the header means its trailing markers are missing, as long as it stops at
//!   a marker boundary (or ends in an empty cell) and ends in a newline; a row that stops after a
//!   marker's x or y value, or a short last row with no newline (a file cut off mid-write), is
//!   [`ReadError::TruncatedRow`]. Non-empty cells beyond the header are
//!   [`ReadError::ColumnCount`].
//! - The first row's `Frame#` is the take's first frame; later rows must count up by one
//!   ([`ReadError::FrameGap`]). The `Time` column must be a number but is otherwise not used: the
//!   rate is `DataRate`.
//! - `NumMarkers` must equal the names listed ([`ReadError::MarkerCountMismatch`]) and `NumFrames`
//!   the data rows ([`ReadError::FrameCountMismatch`]). Neither side wins: fewer rows usually means
//!   a truncated file, and accepting it would silently lose frames; more rows means the header
//!   is wrong in a way that makes the rest doubtful too.
//!
//! Writing always uses millimetres, the shortest decimal text that reads back to the same `f32`
//! (round trips are exact), times to the microsecond, and empty cells for missing samples.

mod header;
pub(crate) mod text;

use std::io::{BufReader, Read, Write};

use self::header::read_header;
use self::text::{check_frame_number, parse_time, Lines};
use crate::error::{ReadError, WriteError};
use crate::Take;

/// Frames to reserve room for up front at most, so a lying `NumFrames` cannot make us allocate
/// gigabytes before reading a single row.
const MAX_RESERVED_FRAMES: usize = 10_000;

/// Reads a TRC take (values converted to millimetres).
///
/// # Errors
/// I/O failure, malformed or truncated content (see the module docs for each rule), unknown
/// units, or a take that breaks a [`Take`] invariant (no markers, duplicate labels).
pub fn read(input: impl Read) -> Result<Take, ReadError> {
    let mut lines = Lines::new(BufReader::new(input));
    let header = read_header(&mut lines)?;
    let n = header.labels.len();
    let mut take = Take::new(header.labels, header.rate_hz, 1);
    take.source_units = header.units;
    let reserve = header.num_frames.min(MAX_RESERVED_FRAMES) * n;
    take.positions.reserve(reserve * 3);
    take.missing.reserve(reserve);

    // The parser keeps its own copy of the labels (for error messages) so the take stays free
    // to grow; a few dozen short strings.
    let row = RowParser {
        labels: take.labels.clone(),
        scale: f64::from(header.units.to_mm()),
    };
    let mut xyz = vec![0.0f32; n * 3];
    let mut gone = vec![false; n];
    let mut next_frame = None;
    let mut first_frame = header.start_frame.unwrap_or(1);
    let mut row_text = String::new();
    // The row is copied out because `lines` stays borrowed while its text is.
    while let Some(line) = lines.next_non_blank()?.map(|(line, text)| {
        row_text.clear();
        row_text.push_str(text);
        line
    }) {
        // A short row is read as trailing missing markers, unless it is an unterminated last
        // line: then the file was cut off and those markers were lost, not missing.
        let complete = lines.terminated();
        let frame = row.parse(line, &row_text, complete, next_frame, &mut xyz, &mut gone)?;
        if next_frame.is_none() {
            first_frame = frame;
        }
        next_frame = Some(frame.wrapping_add(1));
        take.push_frame(&xyz, &gone);
    }
    take.first_frame = first_frame;
    if take.n_frames() != header.num_frames {
        return Err(ReadError::FrameCountMismatch {
            declared: header.num_frames,
            found: take.n_frames(),
        });
    }
    take.validate()?;
    Ok(take)
}

/// Parses data rows against the header's markers.
struct RowParser {
    labels: Vec<String>,
    scale: f64,
}

impl RowParser {
    /// Parses one data row into `xyz` (mm) and `gone`, returning its frame number.
    fn parse(
        &self,
        line: usize,
        text: &str,
        complete: bool,
        expected_frame: Option<i64>,
        xyz: &mut [f32],
        gone: &mut [bool],
    ) -> Result<i64, ReadError> {
        let cells: Vec<&str> = text.split('\t').collect();
        let width = 2 + 3 * self.labels.len();
        if cells.len() < 2 {
            return Err(ReadError::ColumnCount {
                line,
                expected: width,
                found: cells.len(),
            });
        }
        let frame = check_frame_number(cells[0], line, expected_frame, "Frame#")?;
        if parse_time(cells[1]).is_none() {
            return Err(text::bad_cell(
                line,
                1,
                "Time",
                "a time in seconds",
                cells[1],
            ));
        }
        self.check_width(line, &cells, width, complete)?;
        let data = cells.get(2..).unwrap_or(&[]);
        text::parse_samples(line, data, 2, &self.labels, self.scale, xyz, gone)?;
        Ok(frame)
    }

    /// Extra cells must be empty. A short row must stop at a marker boundary or on an empty
    /// cell, and end in a newline (`complete`).
    fn check_width(
        &self,
        line: usize,
        cells: &[&str],
        width: usize,
        complete: bool,
    ) -> Result<(), ReadError> {
        if cells.len() > width {
            if cells[width..].iter().any(|c| !c.trim().is_empty()) {
                return Err(ReadError::ColumnCount {
                    line,
                    expected: width,
                    found: cells.len(),
                });
            }
        } else if cells.len() < width {
            let data = cells.len() - 2;
            let last_blank = cells.last().is_some_and(|c| c.trim().is_empty());
            if !complete || (data % 3 != 0 && !last_blank) {
                return Err(ReadError::TruncatedRow {
                    line,
                    marker: self.labels[data / 3].clone(),
                    cells: data % 3,
                });
            }
        }
        Ok(())
    }
}

/// Writes a TRC take in millimetres.
///
/// # Errors
/// A take that breaks a [`Take`] invariant, a label holding a tab or line break
/// ([`WriteError::LabelUnrepresentable`]), or I/O failure. Nothing is written when the take or a
/// label is rejected.
pub fn write(take: &Take, out: &mut impl Write) -> Result<(), WriteError> {
    take.validate()?;
    text::check_labels(&take.labels, "trc", &['\t', '\n', '\r'])?;
    let (n, frames, rate) = (take.n_markers(), take.n_frames(), take.rate_hz);
    writeln!(out, "PathFileType\t4\t(X/Y/Z)\ttake.trc")?;
    writeln!(
        out,
        "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames"
    )?;
    let first = take.first_frame;
    writeln!(
        out,
        "{rate}\t{rate}\t{frames}\t{n}\tmm\t{rate}\t{first}\t{frames}"
    )?;
    let mut line = String::from("Frame#\tTime");
    for label in &take.labels {
        line.push('\t');
        line.push_str(label);
        line.push_str("\t\t");
    }
    writeln!(out, "{line}")?;
    line.clear();
    line.push('\t');
    for k in 1..=n {
        line.push_str(&format!("\tX{k}\tY{k}\tZ{k}"));
    }
    writeln!(out, "{line}\n")?;
    for f in 0..frames {
        line.clear();
        text::write_row(&mut line, take, f, '\t');
        out.write_all(line.as_bytes())?;
    }
    Ok(())
}
