//! CSV data rows, read in blocks of frames ([`CsvBlocks`]); [`super::read`] is this reader run
//! to the end.

use std::io::BufRead;

use super::header::{parse_comment, parse_header, Meta};
use super::rate;
use crate::error::ReadError;
use crate::take::TakeHeader;
use crate::trc::row_blocks::{NextRow, RowBlocks};
use crate::trc::text::{self, check_frame_number, parse_time, Lines};
use crate::{Take, Units};

/// A CSV file read row block by row block; see [`crate::blocks`]. Without a `rate_hz` comment
/// the header's rate is `None` and every row's time is kept to derive it at the end, as the
/// whole-file reader does (16 bytes a frame).
#[derive(Debug)]
pub struct CsvBlocks<R> {
    header: TakeHeader,
    rows: RowBlocks<CsvRows<R>>,
}

/// The CSV row parser of [`RowBlocks`].
#[derive(Debug)]
struct CsvRows<R> {
    lines: Lines<R>,
    labels: Vec<String>,
    scale: f64,
    /// Columns between `time` and the markers.
    extra: usize,
    next_frame: Option<i64>,
    done: bool,
    /// `(line, time_s)` per row, kept only when the rate must be derived.
    times: Option<Vec<(usize, f64)>>,
    max_decimals: Option<u32>,
}

impl<R: BufRead> CsvBlocks<R> {
    /// Reads the comments, the column header and the first row.
    ///
    /// # Errors
    /// As [`super::read`], for the header and the first row.
    pub fn new(input: R) -> Result<Self, ReadError> {
        let mut lines = Lines::new(input);
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
        let parser = CsvRows {
            lines,
            labels: labels.clone(),
            scale: f64::from(units.to_mm()),
            extra,
            next_frame: None,
            done: false,
            times: meta.rate_hz.is_none().then(Vec::new),
            max_decimals: Some(0),
        };
        let rows = RowBlocks::start(parser, labels.len(), 1)?;
        let header = TakeHeader {
            labels,
            rate_hz: meta.rate_hz,
            first_frame: rows.first_frame(),
            frames: None,
            source_units: units,
        };
        Ok(CsvBlocks { header, rows })
    }

    /// The take's header.
    pub fn header(&self) -> &TakeHeader {
        &self.header
    }

    /// The rate: the comment's, or derived from the time column once every row is read.
    ///
    /// # Errors
    /// [`ReadError::NoRate`] or [`ReadError::UnevenTime`] when it cannot be derived.
    pub fn rate_hz(&self) -> Result<f64, ReadError> {
        let parser = &self.rows.parser;
        match (self.header.rate_hz, &parser.times) {
            (Some(rate), _) => Ok(rate),
            (None, times) => {
                let resolution_s = parser
                    .max_decimals
                    .map_or(0.0, |d| 10f64.powi(-(d.min(300) as i32)));
                rate::derive_rate(times.as_deref().unwrap_or(&[]), resolution_s)
            }
        }
    }

    /// See [`crate::blocks::BlockReader::read_block`].
    ///
    /// # Errors
    /// As [`super::read`], for the rows read.
    pub fn read_block(&mut self, max_frames: usize, block: &mut Take) -> Result<usize, ReadError> {
        self.rows.read_block(max_frames, block)
    }
}

impl<R: BufRead> NextRow for CsvRows<R> {
    fn next_row(
        &mut self,
        _rows: usize,
        xyz: &mut [f32],
        gone: &mut [bool],
    ) -> Result<Option<i64>, ReadError> {
        if self.done {
            return Ok(None);
        }
        // A last row without its newline was cut off mid-write: the take ends cleanly before
        // it (see the module docs).
        let Some((line, row)) = self.lines.next_whole()? else {
            self.done = true;
            return Ok(None);
        };
        let width = 2 + self.extra + xyz.len();
        let cells = text::split_cells(row, b',', width);
        if cells.len() != width {
            let found = cells.len();
            return Err(ReadError::ColumnCount {
                line,
                expected: width,
                found,
            });
        }
        let frame = check_frame_number(cells[0], line, self.next_frame, "frame")?;
        self.next_frame = Some(frame.wrapping_add(1));
        let time_s = parse_time(cells[1])
            .ok_or_else(|| text::bad_cell(line, 1, "time", "a time in seconds", cells[1]))?;
        if let Some(times) = self.times.as_mut() {
            times.push((line, time_s));
            self.max_decimals = self
                .max_decimals
                .zip(rate::decimals(cells[1]))
                .map(|(a, b)| a.max(b));
        }
        let first = 2 + self.extra;
        let (labels, scale) = (&self.labels, self.scale);
        text::parse_samples(line, &cells[first..], first, labels, scale, xyz, gone)?;
        Ok(Some(frame))
    }
}
