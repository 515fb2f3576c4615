//! `emoshift project` streamed: components of every frame, written as they are computed.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use anyhow::{Context, Result};
use ica_core::model::IcaModel;

use super::{label_map, run_pass, source_notices, Frame, FrameSink, PendingOut, Source};
use crate::offline::progress::Progress;

/// What [`project_file`] did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProjectSummary {
    /// What the user should hear about the take ([`crate::offline::take_notices`]).
    pub notices: Vec<String>,
    /// Frames projected.
    pub frames: usize,
    /// Components per frame.
    pub components: usize,
    /// Frames with a marker missing.
    pub masked: usize,
    /// Frames whose components were held (too few markers).
    pub held: usize,
}

/// Writes the component series of the take at `path` under `model` to `out` as CSV,
/// `frame,time,c0,...`, reading and projecting `block_frames` frames at a time. Files over
/// `max_bytes` are refused.
///
/// # Errors
/// Unreadable, malformed or empty take (naming it), a take sharing no marker with the model,
/// an unwritable output.
pub fn project_file(
    model: &IcaModel,
    (path, max_bytes): (&Path, u64),
    out: &Path,
    block_frames: usize,
    progress: &mut dyn Progress,
) -> Result<ProjectSummary> {
    let mut source = Source::open(path, max_bytes)?;
    let map = label_map(model, &source)?;
    let notices = source_notices(model, &source, &map);
    let pending = PendingOut::new(out);
    let file =
        File::create(pending.path()).with_context(|| format!("cannot create {}", out.display()))?;
    let header = source.empty_take();
    let m = model.components();
    let mut csv = Csv {
        out: BufWriter::new(file),
        first_frame: header.first_frame,
        rate_hz: header.rate_hz,
        line: String::new(),
    };
    write!(csv.out, "frame,time")?;
    for k in 0..m {
        write!(csv.out, ",c{k}")?;
    }
    writeln!(csv.out)?;
    let (frames, masked, held) = std::thread::scope(|s| -> Result<(usize, usize, usize)> {
        // The rows are formatted and written on a thread of their own while the next block
        // is projected; two blocks' buffers go round.
        let (full_tx, full_rx) = std::sync::mpsc::sync_channel::<Block>(1);
        let (free_tx, free_rx) = std::sync::mpsc::channel::<Block>();
        let written = s.spawn(move || -> Result<()> {
            for block in full_rx {
                csv.write(&block, m)?;
                let _ = free_tx.send(block);
            }
            csv.out.flush()?;
            Ok(())
        });
        let mut rows = Rows {
            block: Block::default(),
            spare: Some(Block::default()),
            full: full_tx,
            free: free_rx,
            masked: 0,
            held: 0,
        };
        let pass = (&mut source, &map);
        let projected = run_pass(
            model,
            pass,
            block_frames,
            (progress, "projecting"),
            &mut rows,
        );
        let (masked, held) = (rows.masked, rows.held);
        // Closes the channel: the writer flushes and ends.
        drop(rows);
        let written = written
            .join()
            .map_err(|_| anyhow::anyhow!("the output writer panicked"))?
            .with_context(|| format!("cannot write {}", out.display()));
        match (projected, written) {
            (Ok(frames), Ok(())) => Ok((frames, masked, held)),
            // The writer failed first; the projection then found it gone.
            (Err(e), Err(w)) if e.is::<WriterGone>() => Err(w),
            (Err(e), _) | (Ok(_), Err(e)) => Err(e),
        }
    })?;
    pending.commit()?;
    Ok(ProjectSummary {
        notices,
        frames,
        components: m,
        masked,
        held,
    })
}

/// A block of projected frames: the first frame's index and every frame's components.
#[derive(Default)]
struct Block {
    first: usize,
    u: Vec<f32>,
}

/// The CSV output: `frame,time,c0,...` per frame.
struct Csv {
    out: BufWriter<File>,
    first_frame: i64,
    rate_hz: f64,
    /// One row, reused.
    line: String,
}

impl Csv {
    fn write(&mut self, block: &Block, m: usize) -> Result<()> {
        use std::fmt::Write as _;
        for (k, u) in block.u.chunks_exact(m.max(1)).enumerate() {
            let f = block.first + k;
            let time = f as f64 / self.rate_hz;
            self.line.clear();
            write!(self.line, "{},{time:.6}", self.first_frame + f as i64)?;
            for v in u {
                write!(self.line, ",{v}")?;
            }
            self.line.push('\n');
            self.out.write_all(self.line.as_bytes())?;
        }
        Ok(())
    }
}

/// The writer thread stopped: its own error says why.
#[derive(Debug, thiserror::Error)]
#[error("the output writer stopped")]
struct WriterGone;

/// The projection pass: each frame's components into the block, each block to the writer,
/// and the counts the summary reports.
struct Rows {
    block: Block,
    /// An empty block before the writer returns one.
    spare: Option<Block>,
    full: std::sync::mpsc::SyncSender<Block>,
    free: std::sync::mpsc::Receiver<Block>,
    masked: usize,
    held: usize,
}

impl FrameSink for Rows {
    fn frame(&mut self, frame: Frame<'_>) -> Result<()> {
        if self.block.u.is_empty() {
            self.block.first = frame.index;
        }
        self.block.u.extend_from_slice(frame.u);
        self.masked += usize::from(frame.prepared.status.masked);
        self.held += usize::from(frame.prepared.status.held);
        Ok(())
    }

    fn end_block(&mut self) -> Result<()> {
        let mut next = match self.spare.take() {
            Some(spare) => spare,
            None => self.free.recv().map_err(|_| WriterGone)?,
        };
        next.u.clear();
        let block = std::mem::replace(&mut self.block, next);
        Ok(self.full.send(block).map_err(|_| WriterGone)?)
    }
}
