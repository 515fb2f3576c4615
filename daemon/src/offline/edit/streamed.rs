//! `emoshift edit` streamed: each block projected, edited, resynthesised and written before the
//! next is read.

use std::path::Path;

use anyhow::{bail, Context, Result};
use ica_core::model::IcaModel;
use replay::TakeWriter;

use super::{plan, ComponentSums, EditRequest, FrameEditor, Output};
use crate::offline::progress::Progress;
use crate::offline::streamed::{
    label_map, run_pass, source_notices, with_writer, BlockWrite, Frame, FrameSink, Handoff,
    PendingOut, Source,
};
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
/// time. The file is byte for byte what
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
    block_frames: usize,
    progress: &mut dyn Progress,
) -> Result<EditSummary> {
    if request.replace_from.is_some() || request.add_from.is_some() {
        bail!("Copy & Replace and Copy & Add align whole takes: use edit_take");
    }
    // Named here: the file written first is the hidden one (see the module docs).
    if replay::Format::from_path(out).is_none() {
        return Err(replay::WriteError::UnknownFormat(out.into()).into());
    }
    let mut plan = plan(request, model_path, model)?;
    let mut source = Source::open(path, max_bytes)?;
    let map = label_map(model, &source)?;
    let notices = source_notices(model, &source, &map);
    if plan.needs_means() {
        let mut sums = Sums(ComponentSums::new(model.components()));
        let pass = (&mut source, &map);
        run_pass(
            model,
            pass,
            block_frames,
            (progress, "measuring"),
            &mut sums,
        )?;
        plan.settle(model, &sums.0);
        source.rewind()?;
    }
    let header = source.empty_take();
    let output = Output::new(&header, model.labels(), &map);
    let pending = PendingOut::new(out);
    let at = (header.rate_hz, header.first_frame);
    let writer = TakeWriter::create(pending.path(), &output.take.labels, at, source.frames())
        .with_context(|| format!("{}", out.display()))?;
    let spare = output.take.clone();
    // The blocks are encoded and written on a thread of their own while the next is edited.
    let frames = with_writer(spare, TakeOut(writer, out), |handoff| {
        let mut sink = Edit {
            editor: plan.editor(model)?,
            resynth: FrameProcessor::new(model),
            edited: vec![0.0; model.channels()],
            keep_gaps: request.keep_gaps,
            output,
            handoff,
        };
        let pass = (&mut source, &map);
        run_pass(model, pass, block_frames, (progress, "editing"), &mut sink)
    })?;
    pending.commit()?;
    Ok(EditSummary { frames, notices })
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
}

impl FrameSink for Edit<'_> {
    fn frame(&mut self, frame: Frame<'_>) -> Result<()> {
        self.editor.apply(frame.index, frame.u)?;
        let pose = frame.prepared.pose;
        self.resynth
            .resynthesise(pose.as_ref(), frame.u, &mut self.edited)?;
        let edited = (&self.edited[..], frame.model.1);
        self.output
            .push_frame(frame.index, frame.source, edited, self.keep_gaps)
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
