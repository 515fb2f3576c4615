//! Where a streamed command's frames come from: the take file read in blocks, or a take held
//! whole when its header cannot say its rate (a CSV without `rate_hz`).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use replay::blocks::{open_blocks, FileBlocks};
use replay::Take;

/// A take served in blocks; see the module docs.
pub(crate) struct Source {
    path: PathBuf,
    max_bytes: u64,
    kind: Kind,
}

enum Kind {
    /// Boxed: the reader's buffers would make every source as large.
    File(Box<FileBlocks>),
    /// The whole take, and the index of the next frame to serve.
    Memory(Take, usize),
}

impl Source {
    /// Opens `path` (at most `max_bytes`) and reads its header; loads it whole when the
    /// header has no rate.
    ///
    /// # Errors
    /// Unreadable or malformed file, naming it.
    pub(crate) fn open(path: &Path, max_bytes: u64) -> Result<Source> {
        let reader = open_blocks(path, max_bytes).with_context(|| format!("{}", path.display()))?;
        let kind = if reader.header().rate_hz.is_some() {
            Kind::File(Box::new(reader))
        } else {
            drop(reader);
            Kind::Memory(crate::offline::load_take(path)?, 0)
        };
        Ok(Source {
            path: path.to_path_buf(),
            max_bytes,
            kind,
        })
    }

    /// Back to the first frame (the file is opened again).
    ///
    /// # Errors
    /// As [`Source::open`].
    pub(crate) fn rewind(&mut self) -> Result<()> {
        match &mut self.kind {
            Kind::Memory(_, next) => *next = 0,
            Kind::File(_) => *self = Source::open(&self.path, self.max_bytes)?,
        }
        Ok(())
    }

    /// The file.
    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    /// A take of no frames with the take's labels, rate, first frame and units.
    pub(crate) fn empty_take(&self) -> Take {
        match &self.kind {
            Kind::File(r) => r.header().empty_take(),
            Kind::Memory(take, _) => {
                let mut empty = Take::new(take.labels.clone(), take.rate_hz, take.first_frame);
                empty.source_units = take.source_units;
                empty
            }
        }
    }

    /// Marker labels.
    pub(crate) fn labels(&self) -> &[String] {
        match &self.kind {
            Kind::File(r) => &r.header().labels,
            Kind::Memory(take, _) => &take.labels,
        }
    }

    /// Frames the take declares, when known up front.
    pub(crate) fn frames(&self) -> Option<usize> {
        match &self.kind {
            Kind::File(r) => r.header().frames,
            Kind::Memory(take, _) => Some(take.n_frames()),
        }
    }

    /// Replaces `block`'s frames with the next at most `max_frames`; 0 at the end.
    ///
    /// # Errors
    /// The file's read errors, naming it.
    pub(crate) fn read_block(&mut self, max_frames: usize, block: &mut Take) -> Result<usize> {
        match &mut self.kind {
            Kind::File(r) => r
                .read_block(max_frames, block)
                .with_context(|| format!("{}", self.path.display())),
            Kind::Memory(take, next) => {
                let count = max_frames.min(take.n_frames() - *next);
                let (n, start) = (take.n_markers(), *next);
                block.first_frame = take.first_frame + start as i64;
                block.positions.clear();
                block
                    .positions
                    .extend_from_slice(&take.positions[start * n * 3..(start + count) * n * 3]);
                block.missing.clear();
                block
                    .missing
                    .extend_from_slice(&take.missing[start * n..(start + count) * n]);
                *next += count;
                Ok(count)
            }
        }
    }
}
