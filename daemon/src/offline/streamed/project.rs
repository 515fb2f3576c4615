//! `emoshift project` streamed: components of every frame, written as they are computed.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use anyhow::{Context, Result};
use ica_core::model::IcaModel;

use super::{
    label_map, run_pass, source_notices, with_writer, BlockWrite, Frame, FrameSink, Handoff,
    PendingOut, Reuse, Source,
};
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
        path: out,
        first_frame: header.first_frame,
        rate_hz: header.rate_hz,
        components: m,
        line: String::new(),
    };
    write!(csv.out, "frame,time")?;
    for k in 0..m {
        write!(csv.out, ",c{k}")?;
    }
    writeln!(csv.out)?;
    // The rows are formatted and written on a thread of their own while the next block is
    // projected.
    let (frames, masked, held) = with_writer(Block::default(), csv, |handoff| {
        let mut rows = Rows {
            block: Block::default(),
            handoff,
            masked: 0,
            held: 0,
        };
        let pass = (&mut source, &map);
        let stage = (progress, "projecting");
        let frames = run_pass(model, pass, block_frames, stage, Reuse::Off, &mut rows)?;
        Ok((frames, rows.masked, rows.held))
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

/// The CSV output: `frame,time,c0,...` per frame, written on the writer thread.
struct Csv<'a> {
    out: BufWriter<File>,
    path: &'a Path,
    first_frame: i64,
    rate_hz: f64,
    components: usize,
    /// One row, reused.
    line: String,
}

impl Csv<'_> {
    fn rows(&mut self, block: &Block) -> Result<()> {
        use std::fmt::Write as _;
        for (k, u) in block.u.chunks_exact(self.components.max(1)).enumerate() {
            let f = block.first + k;
            let time = f as f64 / self.rate_hz;
            self.line.clear();
            write!(self.line, "{},{time:.6}", self.first_frame + f as i64)?;
            for &v in u {
                self.line.push(',');
                replay::decimal::push_f32(&mut self.line, v);
            }
            self.line.push('\n');
            self.out.write_all(self.line.as_bytes())?;
        }
        Ok(())
    }
}

impl BlockWrite<Block> for Csv<'_> {
    fn write(&mut self, block: &Block) -> Result<()> {
        let path = self.path;
        self.rows(block)
            .with_context(|| format!("cannot write {}", path.display()))
    }

    fn finish(mut self) -> Result<()> {
        let path = self.path;
        self.out
            .flush()
            .with_context(|| format!("cannot write {}", path.display()))
    }
}

/// The projection pass: each frame's components into the block, each block to the writer,
/// and the counts the summary reports.
struct Rows {
    block: Block,
    handoff: Handoff<Block>,
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
        self.handoff.send(&mut self.block, |next| next.u.clear())
    }
}
