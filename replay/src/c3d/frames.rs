//! C3D read in blocks of frames: the header and parameter section are read and checked as the
//! whole-file reader does, then each frame record is decoded by the same per-frame decoder
//! ([`decode::frame_into`]) and missing rule ([`super::push_samples`]). Only our own decoder
//! runs here (c3dio needs the whole file); on files where c3dio and ours agree, as the
//! whole-file reader requires before using c3dio's values, the takes are the same.

use std::io::{BufRead, Chain, Cursor, Read};

use super::binary::{self, BLOCK};
use super::layout::Layout;
use super::{decode, params};
use crate::error::c3d::C3dError;
use crate::error::ReadError;
use crate::take::TakeHeader;
use crate::Take;

/// A C3D file read frame block by frame block; see [`crate::blocks`].
#[derive(Debug)]
pub struct C3dBlocks<R> {
    /// What was read for the header and parameters, from the data start on, then the rest.
    input: Chain<Cursor<Vec<u8>>, R>,
    layout: Layout,
    header: TakeHeader,
    /// One block's frame records, reused.
    records: Vec<u8>,
    /// One block's raw samples, reused.
    xyz: Vec<f32>,
    invalid: Vec<bool>,
    /// Frames read so far.
    next: usize,
}

/// The start of a C3D file: its bytes through the parameter section, and what they say.
pub(crate) struct Head {
    /// The bytes read: the header, the parameter section, at times a little more.
    pub(crate) prefix: Vec<u8>,
    pub(crate) processor: binary::Processor,
    pub(crate) header: binary::Header,
    pub(crate) params: params::Params,
}

/// Reads the header and the parameter section (at most the 255 parameter blocks a header can
/// point at, or up to the data start), leaving `input` after them.
///
/// # Errors
/// As [`super::read`], for the header and parameters.
pub(crate) fn read_head(input: &mut impl Read) -> Result<Head, ReadError> {
    let mut prefix = Vec::with_capacity(BLOCK);
    fill_to(input, &mut prefix, BLOCK)?;
    if prefix.len() < BLOCK {
        return Err(C3dError::TooShort { len: prefix.len() }.into());
    }
    let parameter_block = usize::from(prefix[0]);
    fill_to(input, &mut prefix, parameter_block.max(1) * BLOCK)?;
    let (processor, header) = binary::parse_header(&prefix)?;
    let start = (parameter_block - 1) * BLOCK;
    let end = if header.data_block > parameter_block {
        (header.data_block - 1) * BLOCK
    } else {
        start + usize::from(prefix[start + 2]).max(1) * BLOCK
    };
    fill_to(input, &mut prefix, end)?;
    let params = params::parse(&prefix, parameter_block, header.data_block, processor)?;
    Ok(Head {
        prefix,
        processor,
        header,
        params,
    })
}

/// Reads until `buf` holds `len` bytes or the input ends.
fn fill_to(input: &mut impl Read, buf: &mut Vec<u8>, len: usize) -> Result<(), ReadError> {
    if buf.len() < len {
        let want = (len - buf.len()) as u64;
        input.take(want).read_to_end(buf)?;
    }
    Ok(())
}

impl<R: BufRead> C3dBlocks<R> {
    /// Reads and checks the header and parameter section (at most the 255 parameter blocks a
    /// header can point at, or up to the data start).
    ///
    /// # Errors
    /// As [`super::read`] for the header and parameters; [`C3dError::Truncated`] when
    /// `file_len` cannot hold the declared frames.
    pub fn new(mut input: R, file_len: Option<u64>) -> Result<Self, ReadError> {
        let Head {
            mut prefix,
            processor,
            header: h,
            params,
        } = read_head(&mut input)?;
        let len = file_len.map_or(usize::MAX, |l| usize::try_from(l).unwrap_or(usize::MAX));
        let layout = Layout::new(processor, &h, &params, len)?;
        if layout.data_offset > prefix.len() {
            let gap = (layout.data_offset - prefix.len()) as u64;
            let skipped = std::io::copy(&mut (&mut input).take(gap), &mut std::io::sink())?;
            if skipped < gap {
                return Err(truncated(&layout, 0));
            }
            prefix.clear();
        } else {
            prefix.drain(..layout.data_offset);
        }
        let header = TakeHeader {
            labels: layout.labels.clone(),
            rate_hz: Some(layout.rate_hz),
            first_frame: layout.first_frame,
            frames: Some(layout.frames),
            source_units: layout.units,
        };
        Ok(C3dBlocks {
            input: Cursor::new(prefix).chain(input),
            records: Vec::new(),
            header,
            layout,
            xyz: Vec::new(),
            invalid: Vec::new(),
            next: 0,
        })
    }

    /// The take's header.
    pub fn header(&self) -> &TakeHeader {
        &self.header
    }

    /// See [`crate::blocks::BlockReader::read_block`].
    ///
    /// # Errors
    /// [`C3dError::Truncated`] when the data ends before the declared frames; I/O failure.
    pub fn read_block(&mut self, max_frames: usize, block: &mut Take) -> Result<usize, ReadError> {
        block.positions.clear();
        block.missing.clear();
        block.first_frame = self.layout.first_frame + self.next as i64;
        let count = max_frames.min(self.layout.frames - self.next);
        self.xyz.clear();
        self.invalid.clear();
        // The block's records in one read (as many reads as the input needs to fill it).
        let record = self.layout.frame_bytes();
        self.records.resize(count * record, 0);
        let mut filled = 0;
        while filled < self.records.len() {
            match self.input.read(&mut self.records[filled..]) {
                Ok(0) => return Err(truncated(&self.layout, self.next + filled / record)),
                Ok(n) => filled += n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e.into()),
            }
        }
        for frame in self.records.chunks_exact(record.max(1)) {
            decode::frame_into(frame, &self.layout, &mut self.xyz, &mut self.invalid);
        }
        self.next += count;
        super::push_samples(&self.layout, &self.xyz, &self.invalid, block);
        Ok(count)
    }
}

/// The data ended after `frames` whole frames.
fn truncated(l: &Layout, frames: usize) -> ReadError {
    C3dError::Truncated {
        first: l.first_frame,
        last: l.first_frame + l.frames as i64 - 1,
        needed: l.frames.saturating_mul(l.frame_bytes()),
        available: frames * l.frame_bytes(),
        data_block: l.data_offset / BLOCK + 1,
    }
    .into()
}
