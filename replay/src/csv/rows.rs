//! CSV data rows, read in blocks of frames ([`CsvBlocks`]); [`super::read`] is this reader run
//! to the end.

use std::io::BufRead;

use super::header::{parse_comment, parse_header, Meta};
use super::rate;
use crate::blocks::TakeHeader;
use crate::error::ReadError;
use crate::trc::text::{self, check_frame_number, parse_time, Lines};
use crate::{Take, Units};

/// A CSV file read row block by row block; see [`crate::blocks`]. Without a `rate_hz` comment
/// the header's rate is `None` and every row's time is kept to derive it at the end, as the
/// whole-file reader does (16 bytes a frame).
#[derive(Debug)]
pub struct CsvBlocks<R> {
    lines: Lines<R>,
    header: TakeHeader,
    /// Columns between `time` and the markers.
    extra: usize,
    /// One parsed row, reused; holds the first row until the first block.
    xyz: Vec<f32>,
    gone: Vec<bool>,
    pending: bool,
    next_frame: Option<i64>,
    rows: usize,
    done: bool,
    /// `(line, time_s)` per row, kept only when the rate must be derived.
    times: Vec<(usize, f64)>,
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
        let n = labels.len();
        let mut blocks = CsvBlocks {
            lines,
            header: TakeHeader {
                labels,
                rate_hz: meta.rate_hz,
                first_frame: 1,
                frames: None,
                source_units: meta.units.unwrap_or(Units::Millimetres),
            },
            extra,
            xyz: vec![0.0; n * 3],
            gone: vec![false; n],
            pending: false,
            next_frame: None,
            rows: 0,
            done: false,
            times: Vec::new(),
            max_decimals: Some(0),
        };
        if let Some(frame) = blocks.next_row()? {
            blocks.header.first_frame = frame;
            blocks.pending = true;
        }
        Ok(blocks)
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
        if let Some(rate) = self.header.rate_hz {
            return Ok(rate);
        }
        let resolution_s = self
            .max_decimals
            .map_or(0.0, |d| 10f64.powi(-(d.min(300) as i32)));
        rate::derive_rate(&self.times, resolution_s)
    }

    /// Parses the next data row into the row buffers; `None` at the end of the file.
    fn next_row(&mut self) -> Result<Option<i64>, ReadError> {
        if self.done {
            return Ok(None);
        }
        let Some((line, row)) = self.lines.next_non_blank()? else {
            self.done = true;
            return Ok(None);
        };
        let width = 2 + self.extra + self.xyz.len();
        let cells: Vec<&str> = row.split(',').collect();
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
        if self.header.rate_hz.is_none() {
            self.times.push((line, time_s));
            self.max_decimals = self
                .max_decimals
                .zip(rate::decimals(cells[1]))
                .map(|(a, b)| a.max(b));
        }
        let first = 2 + self.extra;
        let scale = f64::from(self.header.source_units.to_mm());
        let labels = &self.header.labels;
        let (xyz, gone) = (&mut self.xyz, &mut self.gone);
        text::parse_samples(line, &cells[first..], first, labels, scale, xyz, gone)?;
        self.rows += 1;
        Ok(Some(frame))
    }

    /// See [`crate::blocks::BlockReader::read_block`].
    ///
    /// # Errors
    /// As [`super::read`], for the rows read.
    pub fn read_block(&mut self, max_frames: usize, block: &mut Take) -> Result<usize, ReadError> {
        block.positions.clear();
        block.missing.clear();
        let before = self.rows - usize::from(self.pending);
        block.first_frame = self.header.first_frame.wrapping_add(before as i64);
        let mut count = 0;
        while count < max_frames {
            if !std::mem::take(&mut self.pending) && self.next_row()?.is_none() {
                break;
            }
            block.push_frame(&self.xyz, &self.gone);
            count += 1;
        }
        Ok(count)
    }
}
