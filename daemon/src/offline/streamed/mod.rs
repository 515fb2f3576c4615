//! `project` and `edit` from the take file to the output in blocks of frames, so memory holds
//! a block and the model whatever the take's length (issue 18). Every frame goes through the
//! same [`FrameProcessor`] in order, whose state (glitch reference, held pose, held
//! components) crosses block boundaries untouched, so the output is the whole-take path's.
//!
//! - [`project_file`]: one pass.
//! - [`crate::offline::edit::edit_file`] (which lives with the edits): one pass, or two for `--to-emotion` without `--lowpass`, whose offset needs
//!   the take's mean components (the first pass sums them; the file is read again).
//! - Copy & Replace and Copy & Add align another take to all of this one (DTW) and stay on the
//!   whole-take path ([`crate::offline::edit::edit_take`]).
//! - A CSV without `# rate_hz=` only has a rate once its last row is read: it is loaded whole
//!   and then processed in the same blocks.
//!
//! Outputs are written to a hidden file beside the output and renamed over it when complete:
//! a failure half way (a truncated input) leaves no partial file.

mod handoff;
mod output;
mod project;
mod reuse;
mod source;

pub use project::{project_file, ProjectSummary};

use anyhow::{Context, Result};
use ica_core::model::IcaModel;

use crate::offline::progress::Progress;
use crate::offline::takes::frames_in_model_order_into;
use crate::offline::ModelFrames;
use engine::frame::{FrameProcessor, Prepared};
use engine::LabelMap;
pub(crate) use handoff::{with_writer, BlockWrite, Handoff};
pub(crate) use output::PendingOut;
pub use reuse::KEEP_BYTES;
pub(crate) use reuse::{replay_pass, Kept, Reuse};
pub(crate) use source::Source;

/// Frames per block: for a hundred markers the block's buffers (records read, decoded take,
/// model order) hold under a megabyte each and stay in cache from the reader to the pass, and
/// their first use faults in few pages. 4096 (5 MB a buffer) took edit of a 10-minute take
/// 0.73-0.85 s of CPU and 23,000 page faults; 512 took 0.51-0.61 s and 3,900 (issue 35).
pub const BLOCK_FRAMES: usize = 512;

/// One frame as a [`FrameSink`] sees it, projected.
pub(crate) struct Frame<'a> {
    /// Frame index from the take's first frame.
    pub index: usize,
    /// The frame as read (take markers), with its mask; empty in a pass that did not read the
    /// take ([`FrameSink::reads_frames`]).
    pub source: (&'a [f32], &'a [bool]),
    /// The frame in model order, with its mask; in a pass that did not read the take, no
    /// positions and a mask of every marker present.
    pub model: (&'a [f32], &'a [bool]),
    /// What preparing and projecting found.
    pub prepared: Prepared,
    /// The components, for the sink to use or edit.
    pub u: &'a mut [f32],
}

/// What a pass does with each projected frame, and after each block.
pub(crate) trait FrameSink {
    /// One frame, in take order.
    fn frame(&mut self, frame: Frame<'_>) -> Result<()>;
    /// The block's frames are all seen.
    fn end_block(&mut self) -> Result<()> {
        Ok(())
    }
    /// Whether the sink wants no frame from index `index` on (a range ended): the pass stops
    /// reading.
    fn is_past(&self, _index: usize) -> bool {
        false
    }
    /// Whether the sink reads the frames' positions or masks, not only their projections: a
    /// pass whose projections were all kept reads the take again only for a sink that does.
    fn reads_frames(&self) -> bool {
        true
    }
}

/// [`crate::offline::take_notices`] of a source.
pub(crate) fn source_notices(model: &IcaModel, source: &Source, map: &LabelMap) -> Vec<String> {
    let rate_hz = source.empty_take().rate_hz;
    crate::offline::take_notices(model, (source.labels(), rate_hz), map)
}

/// Matches a source's labels to a model's.
pub(crate) fn label_map(model: &IcaModel, source: &Source) -> Result<LabelMap> {
    LabelMap::new(model.labels(), source.labels())
        .with_context(|| format!("{}", source.path().display()))
}

/// A block read and put in model order, or why reading stopped.
type ReadBlock = Result<(replay::Take, ModelFrames)>;

/// Projects each frame of a block (its frames in model order beside it), the first of them
/// frame `index` of the take, or takes its projection back from a first pass, and hands it to
/// `sink`.
fn feed(
    (block, frames): (&replay::Take, &ModelFrames),
    index: usize,
    (processor, u): (&mut FrameProcessor, &mut [f32]),
    reuse: &mut Reuse<'_>,
    sink: &mut dyn FrameSink,
) -> Result<()> {
    for k in 0..block.n_frames() {
        let (xyz, missing) = frames.frame(k);
        let prepared = match reuse.take_back(index + k, u) {
            Some(kept) => kept,
            None => {
                let prepared = processor.project(xyz, missing, u)?;
                reuse.keep(prepared, u, processor);
                prepared
            }
        };
        sink.frame(Frame {
            index: index + k,
            source: (block.frame(k), block.frame_missing(k)),
            model: (xyz, missing),
            prepared,
            u,
        })?;
    }
    Ok(())
}

/// The reader thread of [`run_pass`]: fills the buffers `free` returns with the next block
/// and its frames in model order and sends them on `full`, until the input ends, fails, or
/// the processing side has gone.
fn read_blocks(
    (source, map): (&mut Source, &LabelMap),
    block_frames: usize,
    free: std::sync::mpsc::Receiver<(replay::Take, ModelFrames)>,
    full: std::sync::mpsc::SyncSender<ReadBlock>,
) {
    while let Ok((mut block, mut frames)) = free.recv() {
        let read = match source.read_block(block_frames.max(1), &mut block) {
            Ok(0) => return,
            Ok(_) => {
                let all = 0..block.n_frames();
                frames_in_model_order_into(&block, map, all, &mut frames);
                Ok((block, frames))
            }
            Err(e) => Err(e),
        };
        let failed = read.is_err();
        if full.send(read).is_err() || failed {
            return;
        }
    }
}

/// Projects every frame of `source` in blocks of `block_frames` and hands it to `sink` (until
/// the sink [`FrameSink::is_past`] the next); reports progress as step `name`; returns the
/// frames seen.
///
/// A reader thread decodes the next block (and puts it in model order) while this one
/// processes the current: the frames are processed in order by one processor, as before, and
/// the sink sees them in order. Two blocks' buffers go round between the two threads.
///
/// `reuse` keeps the frames' projections for a second pass, or takes them back from a first.
///
/// # Errors
/// The source's read errors (naming the file), or the sink's.
pub(crate) fn run_pass(
    model: &IcaModel,
    (source, map): (&mut Source, &LabelMap),
    block_frames: usize,
    (progress, name): (&mut dyn Progress, &str),
    mut reuse: Reuse<'_>,
    sink: &mut dyn FrameSink,
) -> Result<usize> {
    progress.step(name, "frames", source.frames().map(|n| n as u64));
    let mut processor = reuse.processor(|| FrameProcessor::new(model));
    let mut u = vec![0.0f32; model.components()];
    let mut index = 0;
    let path = source.path().to_path_buf();
    let empty = source.empty_take();
    std::thread::scope(|s| -> Result<()> {
        let (full_tx, full_rx) = std::sync::mpsc::sync_channel::<ReadBlock>(1);
        let (free_tx, free_rx) = std::sync::mpsc::channel::<(replay::Take, ModelFrames)>();
        for _ in 0..2 {
            // Cannot fail: the receiver is alive.
            let _ = free_tx.send((empty.clone(), ModelFrames::default()));
        }
        s.spawn(move || read_blocks((source, map), block_frames, free_rx, full_tx));
        for read in full_rx {
            let (block, frames) = read?;
            let state = (&mut processor, &mut u[..]);
            feed((&block, &frames), index, state, &mut reuse, sink)?;
            index += block.n_frames();
            sink.end_block()?;
            progress.advance(block.n_frames() as u64);
            if sink.is_past(index) {
                // Dropping the channels ends the reader.
                break;
            }
            // The reader may have finished: buffers it will not need.
            let _ = free_tx.send((block, frames));
        }
        Ok(())
    })?;
    if index == 0 {
        anyhow::bail!("{}: take has no frames", path.display());
    }
    Ok(index)
}
