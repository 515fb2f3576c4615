//! The [`Pipeline`]: the engine's one entry point (the path is drawn in [`crate`]). It owns the
//! streams and every buffer a frame goes through (sized at construction, and per stream when
//! the stream is made).
//!
//! Call order, on the one thread that owns it:
//!
//! 1. [`Pipeline::handle_frame`] per source frame, with the sink every output hangs off: the
//!    processed frame goes to the sink once (or the frame is dropped and counted);
//! 2. [`Pipeline::poll_refusal`] after it: a reason the frame's source should hear;
//! 3. between two frames (a frame boundary, so no frame sees half a change):
//!    [`Pipeline::handle_edit`], [`Pipeline::check_model`] then [`Pipeline::set_model`];
//! 4. every [`SWEEP_SECONDS`] on the caller's clock: [`Pipeline::forget_quiet_streams`].
//!
//! A pipeline made [`Pipeline::without_model`] (a stage that starts the daemon before the
//! performer's model exists) passes every frame through unedited, under its source's labels
//! and frame numbers, and refuses edits ([`EditRefused::NoModel`]); [`Pipeline::set_model`]
//! later rebuilds its streams on the model, edited from their next frame.

use std::sync::Arc;

use ica_core::model::IcaModel;
use protocol::{Control, FrameBuf, FrameTime};

use crate::edit_state::{apply_edit, EditRefused, EditState};
use crate::input::SourceFrame;
use crate::output::Sink;
use crate::streams::{Performer, StreamKey, StreamStatus, Streams};
use crate::Counters;

mod run;
mod setup;

/// A source's frame refused with a reason its source should hear (an OSC source gets
/// `/emoshift/error` on the frame socket); the shell tells it, rate-limited.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Refusal {
    /// The stream refused (its source is `key.source`).
    pub key: StreamKey,
    /// Why.
    pub why: String,
}

/// A model refused because running streams lack some of its markers.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}", describe_mismatch(streams))]
pub struct ModelMismatch {
    /// Each stream it does not fit, with the model's markers the stream's source does not name.
    pub streams: Vec<(String, Vec<String>)>,
}

/// `names` as a short list: the first `shown`, then how many more.
pub fn short_list(names: &[String], shown: usize) -> String {
    let first: Vec<&str> = names.iter().take(shown).map(String::as_str).collect();
    match names.len().saturating_sub(first.len()) {
        0 => first.join(", "),
        more => format!("{} and {more} more", first.join(", ")),
    }
}

fn describe_mismatch(streams: &[(String, Vec<String>)]) -> String {
    let each: Vec<String> = streams
        .iter()
        .map(|(name, missing)| {
            format!(
                "stream {name} lacks {} of its markers: {}",
                missing.len(),
                short_list(missing, 8)
            )
        })
        .collect();
    format!(
        "the model does not fit the running streams, kept the old one: {}",
        each.join("; ")
    )
}

/// Streams at most (bounds memory against spoofed senders).
pub const MAX_SOURCES: usize = 64;
/// Sweeps ([`Pipeline::forget_quiet_streams`]) a stream may stay silent through: at the next
/// it is forgotten, and its slot among [`MAX_SOURCES`] is free again. A stream that comes back
/// is made again on its next frame, under the same id.
pub const QUIET_SWEEPS: u64 = 3;
/// How often the shell sweeps, seconds (for the refusal's words; the shell owns the clock).
pub const SWEEP_SECONDS: u64 = 10;
/// Default rate of a stream passed through without a model (what its recording and the
/// NatNet and QTM servers announce): the common facial capture rate.
pub const DEFAULT_PASSTHROUGH_RATE_HZ: f64 = 120.0;

/// Pipeline settings.
#[derive(Debug, Clone)]
pub struct PipelineConfig {
    /// Low-pass window of the emotion edit (seconds).
    pub lowpass_s: f32,
    /// Largest frame accepted (markers).
    pub max_markers: usize,
    /// The rate of streams without a model (a model's streams have its rate).
    pub passthrough_rate_hz: f64,
}

impl Default for PipelineConfig {
    fn default() -> Self {
        PipelineConfig {
            lowpass_s: crate::edit_state::DEFAULT_LOWPASS_S,
            max_markers: 1_000,
            passthrough_rate_hz: DEFAULT_PASSTHROUGH_RATE_HZ,
        }
    }
}

/// The processing path. See the module docs for the call order.
#[derive(Debug)]
pub struct Pipeline {
    config: PipelineConfig,
    /// The default model; `None`: frames without a performer's model pass through.
    model: Option<Arc<IcaModel>>,
    performers: Vec<Performer>,
    streams: Streams,
    /// Settings of the default model's streams, copied into new streams.
    template: EditState,
    frame_out: FrameBuf,
    /// The time of the frame being handled.
    time_in: FrameTime,
    /// The last refusal the source should hear, taken by the shell after each frame.
    refusal: Option<Refusal>,
    /// Sweeps so far.
    sweeps: u64,
    /// Counters, read by the caller between frames.
    pub counters: Counters,
}

impl Pipeline {
    /// A pipeline over `model`, with optional named performers.
    pub fn new(model: Arc<IcaModel>, performers: Vec<Performer>, config: PipelineConfig) -> Self {
        let template = EditState::for_model(&model, config.lowpass_s);
        Pipeline::with_template(Some(model), template, performers, config)
    }

    /// A pipeline with no default model yet: streams without a performer's model pass their
    /// frames through unedited until [`Pipeline::set_model`].
    pub fn without_model(performers: Vec<Performer>, config: PipelineConfig) -> Self {
        let template = EditState::new(0, &[], config.lowpass_s);
        Pipeline::with_template(None, template, performers, config)
    }

    fn with_template(
        model: Option<Arc<IcaModel>>,
        template: EditState,
        performers: Vec<Performer>,
        config: PipelineConfig,
    ) -> Self {
        Pipeline {
            streams: Streams::new(MAX_SOURCES),
            frame_out: FrameBuf::with_max_markers(config.max_markers),
            time_in: FrameTime::default(),
            refusal: None,
            sweeps: 0,
            counters: Counters::default(),
            template,
            model,
            performers,
            config,
        }
    }

    /// Takes one source frame through its stream ([`crate::Stream::process`]) and gives the
    /// processed frame to `sink`, once. A stream is made on its first frame (its model, its
    /// performer, its label map); a stream whose source relabels it starts over.
    pub fn handle_frame(&mut self, frame: &SourceFrame<'_>, sink: &mut dyn Sink) {
        let key = frame.key;
        if self
            .streams
            .get(&key)
            .is_some_and(|s| !s.has_source_labels(frame.labels))
        {
            self.streams.forget(key.source, key.layout_id);
        }
        self.time_in = frame.time;
        let defaults = setup::Defaults {
            performers: &self.performers,
            model: self.model.as_ref(),
            template: &self.template,
            lowpass_s: self.config.lowpass_s,
            passthrough_rate_hz: self.config.passthrough_rate_hz,
        };
        let io = run::Io {
            frame_out: &mut self.frame_out,
            time: &self.time_in,
            sweep: self.sweeps,
            counters: &mut self.counters,
        };
        let unmatched = io.counters.dropped_unmatched;
        run::frame_step(&mut self.streams, &defaults, frame, io, sink);
        if self.counters.dropped_unmatched > unmatched {
            let why = self.why_no_stream(frame.labels);
            self.refusal = Some(Refusal { key, why });
        }
    }

    /// The refusal of the last frame, if it was refused with a reason for its source.
    pub fn poll_refusal(&mut self) -> Option<Refusal> {
        self.refusal.take()
    }

    /// Forgets the streams no frame reached in the last [`QUIET_SWEEPS`] calls (the shell
    /// calls this every [`SWEEP_SECONDS`]), freeing their slots: a stage whose sources restart
    /// from new ports (a bridge or Motive restarted) would otherwise fill the [`MAX_SOURCES`]
    /// slots with dead streams, and the next one would never be taken. Returns them.
    pub fn forget_quiet_streams(&mut self) -> Vec<StreamKey> {
        self.sweeps += 1;
        match self.sweeps.checked_sub(QUIET_SWEEPS) {
            Some(since) => self.streams.forget_quiet(since),
            None => Vec::new(),
        }
    }

    /// The default model, `None` before one is loaded.
    pub fn model(&self) -> Option<&Arc<IcaModel>> {
        self.model.as_ref()
    }

    /// Streams now.
    pub fn stream_count(&self) -> usize {
        self.streams.len()
    }

    /// The stream of `key`, to read between frames.
    pub fn stream(&self, key: &StreamKey) -> Option<&crate::Stream> {
        self.streams.get(key)
    }

    /// Each stream's counters.
    pub fn stream_status(&self) -> Vec<StreamStatus> {
        self.streams.status(&self.performers)
    }

    /// Whether `model` can replace the default model: every stream running on the default
    /// model (or passed through for want of one) must name all of `model`'s markers, or it
    /// would be left with markers it never sees (or none at all).
    ///
    /// # Errors
    /// The streams it does not fit and the markers each lacks.
    pub fn check_model(&self, model: &IcaModel) -> Result<(), ModelMismatch> {
        let mut streams = Vec::new();
        for (_, stream) in self.streams.iter() {
            if !stream.runs_on(self.model.as_ref()) {
                continue;
            }
            let missing = stream.missing_from_source(model.labels());
            if !missing.is_empty() {
                streams.push((stream.identity.name.clone(), missing));
            }
        }
        match streams.is_empty() {
            true => Ok(()),
            false => Err(ModelMismatch { streams }),
        }
    }

    /// Swaps in a new default model at a frame boundary: streams on the default model are
    /// rebuilt on it, keeping their edit settings; no frame is dropped. Check it with
    /// [`Pipeline::check_model`] first: a stream it does not fit keeps the old model (or
    /// none).
    pub fn set_model(&mut self, model: Arc<IcaModel>) {
        let mut template = EditState::for_model(&model, self.config.lowpass_s);
        template.copy_settings(&self.template);
        self.template = template;
        let old = self.model.replace(Arc::clone(&model));
        for (_, stream) in self.streams.iter_mut() {
            if !stream.runs_on(old.as_ref()) {
                continue;
            }
            // A stream whose labels share nothing with the new model keeps the old one.
            if let Ok(fresh) = stream.rebuilt_on(Arc::clone(&model), self.config.lowpass_s) {
                *stream = fresh;
            }
        }
        self.counters.model_swaps += 1;
    }

    /// Applies an edit control to the template and every stream.
    ///
    /// # Errors
    /// [`EditRefused`] when the default model cannot take it (component out of range, no
    /// emotion component, unknown emotion); streams of other models skip what they cannot take.
    /// [`EditRefused::NoModel`] when there is no model to edit with (no default model, and no
    /// performer's).
    pub fn handle_edit(&mut self, control: &Control) -> Result<(), EditRefused> {
        match &self.model {
            Some(model) => apply_edit(&mut self.template, &Arc::clone(model), control)?,
            None if self.performers.iter().all(|p| p.model.is_none()) => {
                return Err(EditRefused::NoModel);
            }
            None => {}
        }
        for (_, stream) in self.streams.iter_mut() {
            if let Some(m) = stream.model.clone() {
                let _ = apply_edit(&mut stream.edit, &m, control);
            }
        }
        Ok(())
    }

    /// Why a frame made no stream: the stream table is full, or its markers are none of the
    /// model's.
    fn why_no_stream(&self, labels: &[String]) -> String {
        if self.streams.len() >= MAX_SOURCES {
            return format!("the daemon already runs {MAX_SOURCES} streams");
        }
        let Some(default) = &self.model else {
            return format!(
                "its {} labels name no marker; send /mocap/labels with the markers' names",
                labels.len()
            );
        };
        let all = default.labels();
        let model = &all[..all.len().min(4)];
        let why = format!(
            "none of its {} markers ({}) is a marker of the model, whose markers start {}",
            labels.len(),
            short_list(labels, 4),
            model.join(", ")
        );
        match prefix_hint(labels, all) {
            Some(hint) => format!("{why}; {hint}"),
            None => format!(
                "{why}; train the model on takes named as this source names its markers, or \
                 rename them at the source"
            ),
        }
    }
}

/// What to try when `labels` would match `model` without a prefix (Motive's `Face:HeadFront`
/// or `Face_HeadFront` against a model trained on `HeadFront`); `None` when it would not.
fn prefix_hint(labels: &[String], model: &[String]) -> Option<String> {
    for sep in [':', '_'] {
        let matched = labels
            .iter()
            .filter_map(|l| l.split_once(sep))
            .filter(|(_, marker)| model.iter().any(|m| m == marker))
            .count();
        if matched == 0 {
            continue;
        }
        let prefix = labels
            .iter()
            .find_map(|l| l.split_once(sep))
            .map_or(String::new(), |(asset, _)| format!("{asset}{sep}"));
        return Some(format!(
            "without the prefix {prefix:?} {matched} of them are the model's: over NatNet, serve \
             with --natnet-names marker (natnet_names = \"marker\"); over OSC, send the names \
             without it"
        ));
    }
    None
}

#[cfg(test)]
mod tests;
