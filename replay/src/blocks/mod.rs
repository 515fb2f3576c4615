//! Reading a take in blocks of frames, so a long take can go from file to output in bounded
//! memory (issue 18): a [`BlockReader`] gives the take's [`TakeHeader`] first, then fills a
//! [`Take`] with the next block of frames each call. The whole-file readers of the text formats
//! are this reader run to the end, so the two cannot disagree; C3D shares its per-frame
//! decoder and missing rule with the whole-file reader.
//!
//! ```
//! use replay::blocks::BlockReader;
//! use replay::{Format, Take};
//!
//! let mut take = Take::new(vec!["Chin".into()], 120.0, 1);
//! for f in 0..5 {
//!     take.push_frame(&[f as f32, 0.0, 1.0], &[f == 2]);
//! }
//! let mut bytes = Vec::new();
//! replay::write_as(Format::Trc, &take, &mut bytes).expect("a valid take");
//! let mut reader = BlockReader::new(Format::Trc, &bytes[..], None).expect("a valid header");
//! assert_eq!(reader.header().frames, Some(5));
//! let mut block = reader.header().empty_take();
//! let mut seen = 0;
//! while reader.read_block(2, &mut block).expect("valid rows") > 0 {
//!     assert_eq!(block.frame(0), take.frame(seen));
//!     seen += block.n_frames();
//! }
//! assert_eq!(seen, 5);
//! ```

use std::io::{BufRead, BufReader};
use std::path::Path;

use crate::error::ReadError;
use crate::{c3d, csv, trc, Format, Take};

pub use crate::take::TakeHeader;

/// A take file read block by block; see the module docs.
#[derive(Debug)]
pub enum BlockReader<R> {
    /// C3D frame records.
    C3d(c3d::C3dBlocks<R>),
    /// TRC rows.
    Trc(trc::TrcBlocks<R>),
    /// CSV rows.
    Csv(csv::CsvBlocks<R>),
}

impl<R: BufRead> BlockReader<R> {
    /// Reads the header of a take in `format`. `file_len`, when known, lets C3D report a
    /// truncated file before any frame is read.
    ///
    /// # Errors
    /// As the whole-file readers, for the header; a label or rate that breaks a [`Take`]
    /// invariant.
    pub fn new(format: Format, input: R, file_len: Option<u64>) -> Result<Self, ReadError> {
        let reader = match format {
            Format::C3d => BlockReader::C3d(c3d::C3dBlocks::new(input, file_len)?),
            Format::Trc => BlockReader::Trc(trc::TrcBlocks::new(input)?),
            Format::Csv => BlockReader::Csv(csv::CsvBlocks::new(input)?),
        };
        reader.header().validate()?;
        Ok(reader)
    }

    /// The take's header.
    pub fn header(&self) -> &TakeHeader {
        match self {
            BlockReader::C3d(r) => r.header(),
            BlockReader::Trc(r) => r.header(),
            BlockReader::Csv(r) => r.header(),
        }
    }

    /// Replaces `block`'s frames with the next at most `max_frames` frames (its `first_frame`
    /// becomes the number of the first of them) and returns how many; 0 at the end of the
    /// take, where the checks that need every frame run (TRC's frame count, CSV's rate).
    ///
    /// # Errors
    /// As the whole-file readers, for the rows or frames read.
    pub fn read_block(&mut self, max_frames: usize, block: &mut Take) -> Result<usize, ReadError> {
        match self {
            BlockReader::C3d(r) => r.read_block(max_frames, block),
            BlockReader::Trc(r) => r.read_block(max_frames, block),
            BlockReader::Csv(r) => r.read_block(max_frames, block),
        }
    }

    /// The take's rate: the header's, or for a CSV file without one, derived from the time
    /// column once [`BlockReader::read_block`] has returned 0.
    ///
    /// # Errors
    /// [`ReadError::NoRate`] or [`ReadError::UnevenTime`] for a CSV rate that cannot be derived.
    pub fn rate_hz(&self) -> Result<f64, ReadError> {
        match self {
            BlockReader::Csv(r) => r.rate_hz(),
            _ => Ok(self.header().rate_hz.unwrap_or(1.0)),
        }
    }
}

/// The reader [`open_blocks`] returns.
pub type FileBlocks = BlockReader<BufReader<std::io::Take<std::fs::File>>>;

/// Opens a take file for reading in blocks: a regular file of at most `max_bytes`, its format
/// chosen by extension, its header read.
///
/// # Errors
/// [`ReadError::UnknownFormat`], [`ReadError::Open`], or the header's errors.
pub fn open_blocks(path: &Path, max_bytes: u64) -> Result<FileBlocks, ReadError> {
    let format = Format::from_path(path).ok_or_else(|| ReadError::UnknownFormat(path.into()))?;
    let len = std::fs::metadata(path).ok().map(|m| m.len());
    let input = BufReader::new(crate::file::open_bounded(path, max_bytes)?);
    BlockReader::new(format, input, len)
}
