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
    let mut rows = Rows {
        out: BufWriter::new(file),
        first_frame: header.first_frame,
        rate_hz: header.rate_hz,
        masked: 0,
        held: 0,
    };
    write!(rows.out, "frame,time")?;
    for k in 0..model.components() {
        write!(rows.out, ",c{k}")?;
    }
    writeln!(rows.out)?;
    let pass = (&mut source, &map);
    let frames = run_pass(
        model,
        pass,
        block_frames,
        (progress, "projecting"),
        &mut rows,
    )?;
    rows.out
        .flush()
        .with_context(|| format!("cannot write {}", out.display()))?;
    drop(rows.out);
    pending.commit()?;
    Ok(ProjectSummary {
        notices,
        frames,
        components: model.components(),
        masked: rows.masked,
        held: rows.held,
    })
}

/// The CSV rows, and the counts the summary reports.
struct Rows {
    out: BufWriter<File>,
    first_frame: i64,
    rate_hz: f64,
    masked: usize,
    held: usize,
}

impl FrameSink for Rows {
    fn frame(&mut self, frame: Frame<'_>) -> Result<()> {
        let f = frame.index;
        let time = f as f64 / self.rate_hz;
        write!(self.out, "{},{time:.6}", self.first_frame + f as i64)?;
        for v in frame.u.iter() {
            write!(self.out, ",{v}")?;
        }
        writeln!(self.out)?;
        self.masked += usize::from(frame.prepared.status.masked);
        self.held += usize::from(frame.prepared.status.held);
        Ok(())
    }
}
