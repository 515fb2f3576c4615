//! The hand-off between a pass and the thread that writes its output: the pass fills a block
//! while the writer encodes and writes the previous one; two blocks' buffers go round.

use std::sync::mpsc::{channel, sync_channel, Receiver, SyncSender};

use anyhow::Result;

/// What the writer thread does with each block, and once at the end.
pub(crate) trait BlockWrite<B>: Send {
    /// Writes one block.
    ///
    /// # Errors
    /// The output's write errors.
    fn write(&mut self, block: &B) -> Result<()>;
    /// Flushes and closes the output.
    ///
    /// # Errors
    /// The output's write errors.
    fn finish(self) -> Result<()>;
}

/// The pass's end of the hand-off.
pub(crate) struct Handoff<B> {
    /// An empty block before the writer returns one.
    spare: Option<B>,
    full: SyncSender<B>,
    free: Receiver<B>,
}

impl<B> Handoff<B> {
    /// Sends `block` to the writer and puts an empty one (emptied by `clear`) in its place.
    ///
    /// # Errors
    /// [`WriterGone`] when the writer has stopped (its own error says why).
    pub(crate) fn send(&mut self, block: &mut B, clear: impl FnOnce(&mut B)) -> Result<()> {
        let mut next = match self.spare.take() {
            Some(spare) => spare,
            None => self.free.recv().map_err(|_| WriterGone)?,
        };
        clear(&mut next);
        let full = std::mem::replace(block, next);
        Ok(self.full.send(full).map_err(|_| WriterGone)?)
    }
}

/// The writer thread stopped: its own error says why.
#[derive(Debug, thiserror::Error)]
#[error("the output writer stopped")]
pub(crate) struct WriterGone;

/// Runs `pass` with a [`Handoff`] whose blocks `writer` writes on a thread of its own
/// (`spare` is the second block's buffer), then finishes the writer. A writer failure is
/// reported as the writer's own error, not as the pass finding it gone.
///
/// # Errors
/// The pass's errors, or the writer's.
pub(crate) fn with_writer<B: Send, T>(
    spare: B,
    mut writer: impl BlockWrite<B>,
    pass: impl FnOnce(Handoff<B>) -> Result<T>,
) -> Result<T> {
    std::thread::scope(|s| {
        let (full_tx, full_rx) = sync_channel::<B>(1);
        let (free_tx, free_rx) = channel::<B>();
        let written = s.spawn(move || -> Result<()> {
            for block in full_rx {
                writer.write(&block)?;
                // The pass may have finished: a buffer it will not need.
                let _ = free_tx.send(block);
            }
            writer.finish()
        });
        let handoff = Handoff {
            spare: Some(spare),
            full: full_tx,
            free: free_rx,
        };
        // The pass owns (and drops) the sender: the writer then ends.
        let done = pass(handoff);
        let written = written
            .join()
            .map_err(|_| anyhow::anyhow!("the output writer panicked"))?;
        match (done, written) {
            (Ok(value), Ok(())) => Ok(value),
            (Err(e), Err(w)) if e.is::<WriterGone>() => Err(w),
            (Err(e), _) | (Ok(_), Err(e)) => Err(e),
        }
    })
}
