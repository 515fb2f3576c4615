//! The whitened frames FastICA reads once per iteration: the first [`HELD_BYTES`] of them held
//! in memory, the rest in a [`Spill`] file. Held frames cost neither a read out of the page
//! cache nor a conversion from bytes on each iteration (at 10 minutes, 20 components, that was
//! 7 % of FastICA's CPU, all of it between the parallel halves). The hold is bounded, so
//! memory stays flat in the session's length.
//!
//! Spilled frames are the `f32`s' bytes in the machine's own order (the file is anonymous and
//! dies with the process), read straight into the chunk handed on: no conversion on either
//! side, where converting to and from little-endian bytes was a copy of every spilled frame
//! per FastICA iteration.

use anyhow::Result;

use super::spill::Spill;

/// Whitened frames kept in memory at most: at 20 components, 6 chunks of 32,768 frames, all of
/// a session of 27 minutes at 120 Hz and the first 45 % of a 1-hour one.
pub(super) const HELD_BYTES: usize = 16 << 20;

/// Whitened frames of `m` values each, appended in order and read back in chunks.
#[derive(Debug)]
pub(super) struct Whitened {
    m: usize,
    chunk_frames: usize,
    /// The first frames, at most [`HELD_BYTES`] and a whole number of chunks, so the chunks
    /// read back are the same whether a frame was held or spilled.
    held: Vec<f32>,
    held_frames_max: usize,
    spill: Spill,
    /// The chunk read back from the spill.
    chunk: Vec<f32>,
}

impl Whitened {
    /// An empty store of frames of `m` values, read back `chunk_frames` at a time, holding at
    /// most `held_bytes` of them.
    ///
    /// # Errors
    /// The spill file cannot be created.
    pub(super) fn new(m: usize, chunk_frames: usize, held_bytes: usize) -> Result<Self> {
        let (m, chunk_frames) = (m.max(1), chunk_frames.max(1));
        let held_chunks = held_bytes / (4 * m * chunk_frames);
        Ok(Self {
            m,
            chunk_frames,
            held: Vec::new(),
            held_frames_max: held_chunks * chunk_frames,
            spill: Spill::new(4 * m)?,
            chunk: Vec::new(),
        })
    }

    /// Values per frame.
    pub(super) fn width(&self) -> usize {
        self.m
    }

    /// Frames stored.
    pub(super) fn frames(&self) -> usize {
        self.held.len() / self.m + self.spill.records()
    }

    /// Appends whole frames.
    ///
    /// # Errors
    /// Writing the spill fails (a full disk).
    pub(super) fn push(&mut self, z: &[f32]) -> Result<()> {
        debug_assert_eq!(z.len() % self.m, 0);
        let room = self.held_frames_max - self.held.len() / self.m;
        let hold = if self.spill.records() == 0 {
            room.min(z.len() / self.m) * self.m
        } else {
            0
        };
        self.held.extend_from_slice(&z[..hold]);
        if hold < z.len() {
            self.spill.push(bytemuck::cast_slice(&z[hold..]))?;
        }
        Ok(())
    }

    /// Calls `each` with every frame in order, [`Self::new`]'s `chunk_frames` at a time.
    ///
    /// # Errors
    /// Reading the spill fails, or `each` does.
    pub(super) fn for_each_chunk(
        &mut self,
        each: &mut dyn FnMut(&[f32]) -> Result<()>,
    ) -> Result<()> {
        for chunk in self.held.chunks(self.chunk_frames * self.m) {
            each(chunk)?;
        }
        let (spilled, mut first) = (self.spill.records(), 0);
        while first < spilled {
            let n = (spilled - first).min(self.chunk_frames);
            self.chunk.resize(n * self.m, 0.0);
            self.spill
                .read_at(first, bytemuck::cast_slice_mut(&mut self.chunk))?;
            each(&self.chunk)?;
            first += n;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
