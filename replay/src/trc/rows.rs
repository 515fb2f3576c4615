//! TRC data rows, read in blocks of frames ([`TrcBlocks`]); [`super::read`] is this reader run
//! to the end.

use std::io::BufRead;

use super::header::read_header;
use super::row_blocks::{NextRow, RowBlocks};
use super::text::{self, check_frame_number, parse_time, Lines};
use crate::error::ReadError;
use crate::take::TakeHeader;
use crate::Take;

/// A TRC file read row block by row block; see [`crate::blocks`].
#[derive(Debug)]
pub struct TrcBlocks<R> {
    header: TakeHeader,
    rows: RowBlocks<TrcRows<R>>,
}

/// The TRC row parser of [`RowBlocks`].
#[derive(Debug)]
struct TrcRows<R> {
    lines: Lines<R>,
    row: RowParser,
    /// The current row's text.
    text: String,
    next_frame: Option<i64>,
    /// `NumFrames`.
    declared: usize,
    done: bool,
}

impl<R: BufRead> TrcBlocks<R> {
    /// Reads the header and the first row.
    ///
    /// # Errors
    /// As [`super::read`], for the header and the first row.
    pub fn new(input: R) -> Result<Self, ReadError> {
        let mut lines = Lines::new(input);
        let h = read_header(&mut lines)?;
        let parser = TrcRows {
            lines,
            row: RowParser {
                labels: h.labels.clone(),
                scale: f64::from(h.units.to_mm()),
            },
            text: String::new(),
            next_frame: None,
            declared: h.num_frames,
            done: false,
        };
        let rows = RowBlocks::start(parser, h.labels.len(), h.start_frame.unwrap_or(1))?;
        let header = TakeHeader {
            labels: h.labels,
            rate_hz: Some(h.rate_hz),
            first_frame: rows.first_frame(),
            frames: Some(h.num_frames),
            source_units: h.units,
        };
        Ok(TrcBlocks { header, rows })
    }

    /// The take's header.
    pub fn header(&self) -> &TakeHeader {
        &self.header
    }

    /// See [`crate::blocks::BlockReader::read_block`].
    ///
    /// # Errors
    /// As [`super::read`], for the rows read; [`ReadError::FrameCountMismatch`] at the end.
    pub fn read_block(&mut self, max_frames: usize, block: &mut Take) -> Result<usize, ReadError> {
        self.rows.read_block(max_frames, block)
    }
}

impl<R: BufRead> NextRow for TrcRows<R> {
    /// At the end of the file, checks the row count against `NumFrames`.
    fn next_row(
        &mut self,
        rows: usize,
        xyz: &mut [f32],
        gone: &mut [bool],
    ) -> Result<Option<i64>, ReadError> {
        if self.done {
            return Ok(None);
        }
        if rows == self.declared {
            // The header wins: rows past `NumFrames` are a recording's frames written after its
            // header was last updated (`emoshift repair` counts them), or junk.
            self.done = true;
            return Ok(None);
        }
        // The row is copied out because `lines` stays borrowed while its text is.
        let Some((line, text)) = self.lines.next_non_blank()? else {
            self.done = true;
            if rows < self.declared {
                let (declared, found) = (self.declared, rows);
                return Err(ReadError::FrameCountMismatch { declared, found });
            }
            return Ok(None);
        };
        self.text.clear();
        self.text.push_str(text);
        // A short row is read as trailing missing markers, unless it is an unterminated last
        // line: then the file was cut off and those markers were lost, not missing.
        let complete = self.lines.terminated();
        let frame = self
            .row
            .parse(line, &self.text, complete, self.next_frame, xyz, gone)?;
        self.next_frame = Some(frame.wrapping_add(1));
        Ok(Some(frame))
    }
}

/// Parses data rows against the header's markers.
#[derive(Debug)]
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
        let width = 2 + 3 * self.labels.len();
        let cells = text::split_cells(text, b'\t', width);
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
