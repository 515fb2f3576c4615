//! `analyze` over a session of any length in bounded memory (issue 18): the takes are read
//! sentence by sentence, each through the same block reader and [`FrameProcessor`] path as
//! `project`, and a sentence's series are dropped once its pairs, means and moments are in
//! [`SessionStats`]. Three reads, each for a reason:
//!
//! 1. Headers first: the DTW band of every pair is a share of the session's longest take, so
//!    every take's length is needed before the first pair (C3D and TRC declare it; a CSV is
//!    counted). This also refuses a missing or empty take before hours of work.
//! 2. Every take once, sentence by sentence. The region metrics need the emotion set, known
//!    only at the end, so the moments they need for any set are kept instead of a second pass.
//! 3. The few takes the timeline chart draws (at most ten), again: which ones depends on the
//!    emotion levels, also known only at the end.
//!
//! A take the manifest trims (`start`/`end`) is loaded whole, cut, and projected as
//! [`super::project_session`] does: its first kept frame starts the processor's state, as in a
//! take written by `convert --start/--end`. One take is held at a time, never the session.
//!
//! [`FrameProcessor`]: engine::frame::FrameProcessor

use std::collections::BTreeMap;

use anyhow::{bail, Result};
use ica_core::model::IcaModel;
use replay::session::Session;

use crate::offline::TakeInput;

use super::stats::{SessionStats, TakeSeries};
use super::svg::{timeline_takes, TimelineTake};
use super::{Inputs, Report};
use crate::offline::progress::{Progress, Silent};
use crate::offline::streamed::{self, Frame, FrameSink, Source, BLOCK_FRAMES};
use crate::offline::takes::input_limit;

/// Analyses the session at `session` on `inputs.model`, reporting progress in takes; returns
/// the report and the takes its timeline draws (for [`super::write_report`]).
///
/// # Errors
/// A take that cannot be read or shares no marker with the model, or a metric that cannot be
/// computed.
pub fn analyze_session(
    inputs: &Inputs<'_>,
    session: &Session,
    regions: &BTreeMap<String, Vec<usize>>,
    progress: &mut dyn Progress,
) -> Result<(Report, Vec<TimelineTake>)> {
    let model = inputs.model;
    let takes_in: Vec<TakeInput> = crate::offline::session_inputs(session).collect();
    let frames = take_frames(&takes_in, progress)?;
    let longest = frames.iter().copied().max().unwrap_or(0);
    let mut stats = SessionStats::new(model.components(), longest);
    progress.step("analysing", "takes", Some(session.takes.len() as u64));
    for group in sentence_groups(session) {
        let series: Vec<Vec<f64>> = group
            .iter()
            .map(|&i| {
                let u = project(model, &takes_in[i], frames[i])?;
                check_length(session, i, u.len() / model.components(), frames[i])?;
                progress.advance(1);
                Ok(u.into_iter().map(f64::from).collect())
            })
            .collect::<Result<_>>()?;
        let takes: Vec<TakeSeries<'_>> = group
            .iter()
            .zip(&series)
            .map(|(&index, s)| {
                let entry = &session.takes[index];
                TakeSeries {
                    index,
                    file: &entry.file,
                    sentence: &entry.sentence,
                    emotion: &entry.emotion,
                    series: s,
                }
            })
            .collect();
        stats.add_group(&takes)?;
    }
    let report = stats.finish(inputs, regions)?;
    let shown = timeline_takes(&report);
    progress.step("timeline", "takes", Some(shown.len() as u64));
    let mut timeline = Vec::with_capacity(shown.len());
    for i in shown {
        let entry = &session.takes[i];
        timeline.push(TimelineTake {
            sentence: entry.sentence.clone(),
            emotion: entry.emotion.clone(),
            u: project(model, &takes_in[i], frames[i])?,
        });
        progress.advance(1);
    }
    Ok((report, timeline))
}

/// Each take's frame count (of its range), from its header when it declares one, else by
/// reading it.
fn take_frames(inputs: &[TakeInput], progress: &mut dyn Progress) -> Result<Vec<usize>> {
    progress.step("reading headers", "takes", Some(inputs.len() as u64));
    let mut frames = Vec::with_capacity(inputs.len());
    for input in inputs {
        let path = &input.path;
        let mut source = Source::open(path, input_limit())?;
        let n = match source.frames() {
            Some(n) => n,
            None => {
                let (mut block, mut n) = (source.empty_take(), 0);
                while source.read_block(BLOCK_FRAMES, &mut block)? > 0 {
                    n += block.n_frames();
                }
                n
            }
        };
        if n == 0 {
            bail!("{}: take has no frames", path.display());
        }
        let head = source.empty_take();
        frames.push(input.frames(head.first_frame, head.rate_hz, n)?.len());
        progress.advance(1);
    }
    Ok(frames)
}

/// The manifest's take indices grouped by sentence, groups in order of first appearance,
/// takes in manifest order within a group: all the takes a sentence's pairs need.
fn sentence_groups(session: &Session) -> Vec<Vec<usize>> {
    let mut at: BTreeMap<&str, usize> = BTreeMap::new();
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (i, entry) in session.takes.iter().enumerate() {
        let g = *at.entry(&entry.sentence).or_insert_with(|| {
            groups.push(Vec::new());
            groups.len() - 1
        });
        groups[g].push(i);
    }
    groups
}

/// A take read while it was being analysed must be as long as its header said: the band of
/// every pair came from the headers.
fn check_length(session: &Session, i: usize, got: usize, expected: usize) -> Result<()> {
    if got != expected {
        let path = session.path_of(&session.takes[i]);
        bail!(
            "{}: {got} frames read, {expected} when the session was scanned (file changed?)",
            path.display()
        );
    }
    Ok(())
}

/// Collects the components of every frame.
struct Components(Vec<f32>);

impl FrameSink for Components {
    fn frame(&mut self, frame: Frame<'_>) -> Result<()> {
        self.0.extend_from_slice(frame.u);
        Ok(())
    }
}

/// The components of one take of `frames` frames (frames x m), read in blocks; a trimmed take
/// is loaded and cut first (see the module docs).
fn project(model: &IcaModel, input: &TakeInput, frames: usize) -> Result<Vec<f32>> {
    if !input.range.is_whole() {
        let take = input.load(replay::C3dDecoding::CrossChecked)?;
        let map = crate::offline::match_take(model, &take, &input.path)?;
        let model_frames = crate::offline::to_model_order(&take, &map);
        return Ok(crate::offline::project_take(model, &model_frames)?.u);
    }
    let mut source = Source::open(&input.path, input_limit())?;
    let map = streamed::label_map(model, &source)?;
    // `frames` comes from the header, which may lie: reserve at most one block up front and
    // let the read show the true length (checked against the header afterwards).
    let reserve = frames.min(BLOCK_FRAMES) * model.components();
    let mut sink = Components(Vec::with_capacity(reserve));
    let progress = (&mut Silent as &mut dyn Progress, "");
    streamed::run_pass(
        model,
        (&mut source, &map),
        BLOCK_FRAMES,
        progress,
        streamed::Reuse::Off,
        &mut sink,
    )?;
    Ok(sink.0)
}
