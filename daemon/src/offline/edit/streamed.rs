//! `emoshift edit` streamed: each block projected, edited, resynthesised and written before the
//! next is read.
//!
//! With a range (`--start`/`--end`), the frames before it are read and edited but not written,
//! so the low-pass, the glitch reference and the held pose reach the range as they would in
//! the whole take, and reading stops after it: the output is the same range cut from the whole
//! edit, its first frame numbered as in the input. A `--to-emotion` without `--lowpass` still
//! measures the whole take's mean (its first pass), as the whole edit does. That pass keeps
//! its frames' projections, up to a budget of memory, and the edit takes them back
//! ([`crate::offline::streamed::Kept`]).

use std::path::Path;

use anyhow::{bail, Context, Result};
use ica_core::model::IcaModel;
use replay::TakeWriter;

use super::{plan, ComponentSums, EditRequest, FrameEditor, Output};
use crate::offline::progress::Progress;
use crate::offline::streamed::{
    label_map, replay_pass, run_pass, source_notices, with_writer, BlockWrite, Frame, FrameSink,
    Handoff, Kept, PendingOut, Reuse, Source,
};
use crate::offline::trim::{Cut, Span};
use engine::frame::FrameProcessor;

/// What [`edit_file`] did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EditSummary {
    /// Frames written.
    pub frames: usize,
    /// What the user should hear about the take ([`crate::offline::take_notices`]).
    pub notices: Vec<String>,
}

/// Edits the take at `path` (at most `max_bytes`) under `model` (from `model_path`) as
/// `request` asks and writes it to `out` (format by extension), `block_frames` frames at a
/// time (`streaming`'s first). A two-pass edit keeps up to `streaming`'s second, in bytes, of
/// the first pass's projections for the second
/// ([`crate::offline::streamed::KEEP_BYTES`] by default). The file is byte for byte what
/// [`crate::offline::edit::edit_take`] and [`replay::save`] give, except that a TRC or C3D
/// output of a CSV input (no frame count in its header) gets a padded header.
///
/// # Errors
/// As `edit_take`; Copy & Replace and Copy & Add are refused here (they need the whole take).
pub fn edit_file(
    (model_path, model): (&Path, &IcaModel),
    (path, max_bytes): (&Path, u64),
    request: &EditRequest,
    out: &Path,
    streaming @ (block_frames, _): (usize, usize),
    progress: &mut dyn Progress,
) -> Result<EditSummary> {
    streamable(request, out)?;
    let mut plan = plan(request, model_path, model)?;
    let mut source = Source::open(path, max_bytes)?;
    let map = label_map(model, &source)?;
    let notices = source_notices(model, &source, &map);
    let mut kept = None;
    if plan.needs_means() {
        kept = Some(measure(
            model,
            (&mut source, &map),
            streaming,
            &mut *progress,
            &mut plan,
        )?);
    }
    let header = source.empty_take();
    let (span, cut, declared) = range_of(&header, source.frames(), request)?;
    let output = Output::new(&header, model.labels(), &map);
    let pending = PendingOut::new(out);
    let at = (header.rate_hz, header.first_frame + cut.from as i64);
    let writer = TakeWriter::create(pending.path(), &output.take.labels, at, declared)
        .with_context(|| format!("{}", out.display()))?;
    let spare = output.take.clone();
    // The blocks are encoded and written on a thread of their own while the next is edited.
    let (read, frames) = with_writer(spare, TakeOut(writer, out), |handoff| {
        let sink = Edit {
            editor: plan.editor(model)?,
            resynth: FrameProcessor::new(model),
            edited: vec![0.0; model.channels()],
            keep_gaps: request.keep_gaps,
            output,
            handoff,
            cut,
            written: 0,
        };
        let pass = (&mut source, &map);
        sink.run(model, pass, (kept.as_ref(), block_frames), progress)
    })?;
    if frames == 0 {
        // Only a take whose length its header does not give gets here (else `check` said it).
        bail!("{}", span.nothing_kept(Some(read)));
    }
    pending.commit()?;
    Ok(EditSummary { frames, notices })
}

/// Refuses what the streamed edit cannot do, before any file is touched.
fn streamable(request: &EditRequest, out: &Path) -> Result<()> {
    if request.replace_from.is_some() || request.add_from.is_some() {
        bail!("Copy & Replace and Copy & Add align whole takes: use edit_take");
    }
    // Named here: the file written first is the hidden one (see the module docs).
    if replay::Format::from_path(out).is_none() {
        return Err(replay::WriteError::UnknownFormat(out.into()).into());
    }
    Ok(())
}

/// The range `request` writes of a take with `header`'s numbering and `frames` frames (when
/// known), and the frames it keeps (likewise).
///
/// # Errors
/// A range that keeps no frame.
fn range_of(
    header: &replay::Take,
    frames: Option<usize>,
    request: &EditRequest,
) -> Result<(Span, Cut, Option<usize>)> {
    let span = Span {
        first_frame: header.first_frame,
        rate_hz: header.rate_hz,
    };
    let cut = Cut::new((span.first_frame, span.rate_hz), request.start, request.end);
    let kept = cut.check(span, frames)?;
    Ok((span, cut, kept.map(|range| range.len())))
}

/// The first pass of a mean-based edit: the take's mean components settle `plan`; the source
/// is rewound for the edit. Returns the frames' projections, kept up to `keep_bytes`.
fn measure(
    model: &IcaModel,
    (source, map): (&mut Source, &engine::LabelMap),
    (block_frames, keep_bytes): (usize, usize),
    progress: &mut dyn Progress,
    plan: &mut super::Plan,
) -> Result<Kept> {
    let mut kept = Kept::new(keep_bytes, model.components(), source.frames());
    let mut sums = Sums(ComponentSums::new(model.components()));
    let pass = (&mut *source, map);
    let stage = (progress, "measuring");
    run_pass(
        model,
        pass,
        block_frames,
        stage,
        Reuse::Keep(&mut kept),
        &mut sums,
    )?;
    plan.settle(model, &sums.0);
    source.rewind()?;
    Ok(kept)
}

/// The first pass of a mean-based edit.
struct Sums(ComponentSums);

impl FrameSink for Sums {
    fn frame(&mut self, frame: Frame<'_>) -> Result<()> {
        self.0.add(frame.u);
        Ok(())
    }
}

/// The edit pass: edit, resynthesise, assemble each block, and hand it to the writer.
struct Edit<'a> {
    editor: FrameEditor,
    /// Resynthesis has its own processor, as in the whole-take path.
    resynth: FrameProcessor,
    edited: Vec<f32>,
    keep_gaps: bool,
    output: Output<'a>,
    handoff: Handoff<replay::Take>,
    /// The frames written (all without a range).
    cut: Cut,
    written: usize,
}

impl Edit<'_> {
    /// The edit pass: over the projections `kept` by the first pass when they are the whole
    /// take's and nothing else of it is needed, else over the take read again (taking back
    /// what was kept). Returns the frames seen and the frames written.
    fn run(
        mut self,
        model: &IcaModel,
        pass: (&mut Source, &engine::LabelMap),
        (kept, block_frames): (Option<&Kept>, usize),
        progress: &mut dyn Progress,
    ) -> Result<(usize, usize)> {
        let stage = (progress, "editing");
        let read = match kept {
            Some(kept) if kept.is_whole() && !self.reads_frames() => {
                replay_pass(kept, (model.markers(), block_frames), stage, &mut self)?
            }
            _ => {
                let reuse = kept.map_or(Reuse::Off, Reuse::TakeBack);
                run_pass(model, pass, block_frames, stage, reuse, &mut self)?
            }
        };
        Ok((read, self.written))
    }
}

impl FrameSink for Edit<'_> {
    fn frame(&mut self, frame: Frame<'_>) -> Result<()> {
        // Frames before the range are edited too: the edit's state reaches it as in the
        // whole take.
        self.editor.apply(frame.index, frame.u)?;
        if !self.cut.keeps(frame.index) {
            return Ok(());
        }
        let pose = frame.prepared.pose;
        self.resynth
            .resynthesise(pose.as_ref(), frame.u, &mut self.edited)?;
        let edited = (&self.edited[..], frame.model.1);
        self.written += 1;
        self.output
            .push_frame(frame.index, frame.source, edited, self.keep_gaps)
    }

    fn is_past(&self, index: usize) -> bool {
        self.cut.is_past(index)
    }

    /// The edited model markers replace the take's, and its gaps are filled: only the take's
    /// gaps (`keep_gaps`) and its markers the model lacks are read from it.
    fn reads_frames(&self) -> bool {
        self.keep_gaps || self.output.copies_extra()
    }

    fn end_block(&mut self) -> Result<()> {
        self.handoff.send(&mut self.output.take, |next| {
            next.positions.clear();
            next.missing.clear();
        })
    }
}

/// The edited take's file, written on the writer thread.
struct TakeOut<'a>(TakeWriter, &'a Path);

impl BlockWrite<replay::Take> for TakeOut<'_> {
    fn write(&mut self, block: &replay::Take) -> Result<()> {
        let out = self.1;
        self.0
            .write_block(block)
            .with_context(|| format!("{}", out.display()))
    }

    fn finish(self) -> Result<()> {
        let out = self.1;
        self.0
            .finish()
            .with_context(|| format!("{}", out.display()))
    }
}
