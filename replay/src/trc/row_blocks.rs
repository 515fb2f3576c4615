//! What the two text formats' block readers share: one parsed row in reused buffers, the first
//! row read with the header (it names the take's first frame) and held for the first block,
//! and the blocks filled row by row. Each format supplies only its row parser ([`NextRow`]).

use crate::error::ReadError;
use crate::Take;

/// Frames to reserve room for up front at most, so a large block size cannot make us allocate
/// gigabytes before reading a single row.
const MAX_RESERVED_FRAMES: usize = 10_000;

/// A format's data-row parser.
pub(crate) trait NextRow {
    /// Parses the next data row into `xyz` (mm) and `gone` and returns its frame number;
    /// `None` at the end of the file, once the format's end-of-file checks pass. `rows` rows
    /// were read before this one.
    fn next_row(
        &mut self,
        rows: usize,
        xyz: &mut [f32],
        gone: &mut [bool],
    ) -> Result<Option<i64>, ReadError>;
}

/// Rows served in blocks; see the module docs.
#[derive(Debug)]
pub(crate) struct RowBlocks<P> {
    pub(crate) parser: P,
    xyz: Vec<f32>,
    gone: Vec<bool>,
    /// The last row parsed is not yet in a block.
    pending: bool,
    rows: usize,
    first_frame: i64,
}

impl<P: NextRow> RowBlocks<P> {
    /// Reads the first row of a take of `markers` markers; the first frame is its number, or
    /// `no_rows_first` when there is none.
    pub(crate) fn start(parser: P, markers: usize, no_rows_first: i64) -> Result<Self, ReadError> {
        let mut rows = RowBlocks {
            parser,
            xyz: vec![0.0; markers * 3],
            gone: vec![false; markers],
            pending: false,
            rows: 0,
            first_frame: no_rows_first,
        };
        if let Some(frame) = rows.next_row()? {
            rows.first_frame = frame;
            rows.pending = true;
        }
        Ok(rows)
    }

    /// The number of the take's first frame.
    pub(crate) fn first_frame(&self) -> i64 {
        self.first_frame
    }

    fn next_row(&mut self) -> Result<Option<i64>, ReadError> {
        let row = self
            .parser
            .next_row(self.rows, &mut self.xyz, &mut self.gone)?;
        self.rows += usize::from(row.is_some());
        Ok(row)
    }

    /// See [`crate::blocks::BlockReader::read_block`].
    pub(crate) fn read_block(
        &mut self,
        max_frames: usize,
        block: &mut Take,
    ) -> Result<usize, ReadError> {
        block.positions.clear();
        block.missing.clear();
        let reserve = max_frames.min(MAX_RESERVED_FRAMES) * self.gone.len();
        block.positions.reserve(reserve * 3);
        block.missing.reserve(reserve);
        let before = self.rows - usize::from(self.pending);
        block.first_frame = self.first_frame.wrapping_add(before as i64);
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
