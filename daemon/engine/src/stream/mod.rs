//! One stream: a source's frames of one layout, with its own frame order, edit state,
//! low-pass state and per-frame buffers, processed by [`Stream::process`].
//!
//! A stream without a model ([`Stream::passthrough`]: the daemon started before the
//! performer's model exists) passes its frames through unedited, under the source's labels,
//! missing markers as missing; a model loaded later rebuilds it ([`Stream::rebuilt_on`]).

use std::sync::Arc;

use ica_core::model::IcaModel;
use protocol::{StreamTag, MAX_STREAM_NAME_BYTES};

use super::edit_state::EditState;
use super::frame::FrameProcessor;
use super::layout::{LabelMap, LayoutError};

mod order;
mod process;
pub use order::{Order, RESTART_FRAMES, RESTART_RUN};

/// Who a stream is to its subscribers: `/emoshift/stream ,is`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Identity {
    /// Stable for the daemon's session; also the layout id of its `/mocap/labels`.
    pub id: i32,
    /// The performer's name, or `ip:port/layout` when none is configured; at most
    /// [`MAX_STREAM_NAME_BYTES`].
    pub name: String,
}

impl Identity {
    /// The identity of stream `id`: `name` cut to [`MAX_STREAM_NAME_BYTES`] at a character
    /// boundary.
    pub fn new(id: i32, name: &str) -> Identity {
        let mut end = name.len().min(MAX_STREAM_NAME_BYTES);
        while !name.is_char_boundary(end) {
            end -= 1;
        }
        Identity {
            id,
            name: name[..end].replace('\0', "?"),
        }
    }

    /// The tag the outputs carry.
    pub fn tag(&self) -> StreamTag<'_> {
        StreamTag {
            id: self.id,
            name: &self.name,
        }
    }
}

/// What [`Stream::process`] made of a frame that came through.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Outcome {
    /// Frame numbers since the stream's previous processed frame (1 = none lost).
    pub frames_since_last: u32,
    /// The stream's labels go out with this frame: its first, then once a second of frames.
    pub labels_due: bool,
}

/// One stream's state and buffers, all sized from its model at creation.
#[derive(Debug)]
pub struct Stream {
    /// Who it is to subscribers.
    pub identity: Identity,
    /// The model used; `None`: no model, frames pass through unedited.
    pub model: Option<Arc<IcaModel>>,
    /// The model's rate, or the rate given to a stream without one.
    rate_hz: f64,
    /// Performer index, if a performer owns the stream.
    pub performer: Option<usize>,
    /// The live edit.
    pub edit: EditState,
    /// The source's labels (shared with the source), to build the stream again on another
    /// model and to notice the source relabelling it.
    source_labels: Arc<[String]>,
    /// `None` without a model.
    processor: Option<FrameProcessor>,
    map: LabelMap,
    /// Missing flags in source order.
    source_missing: Vec<bool>,
    /// Frame in model order.
    xyz: Vec<f32>,
    /// Missing flags in model order.
    missing: Vec<bool>,
    /// Components.
    u: Vec<f32>,
    /// Components before the edit (what the monitor page draws beside the edited ones).
    u_in: Vec<f32>,
    /// Edited frame in model order.
    out: Vec<f32>,
    /// Frames since the labels last went out (0: not yet).
    frames_since_labels: u32,
    last_frame: Option<i32>,
    /// Older frames in a row, each the one after the one before: `(count, last of them)`.
    stale_run: (u32, i32),
    /// Frames taken in order (processed).
    pub frames: u64,
    /// Duplicate frame numbers dropped.
    pub duplicates: u64,
    /// Out-of-order (older) frames dropped.
    pub stale: u64,
    /// The pipeline's sweep count when a frame last reached the stream (a stream quiet for a
    /// few sweeps is forgotten).
    pub heard_sweep: u64,
}

impl Stream {
    /// Builds a stream for `source_labels` on `model`.
    ///
    /// # Errors
    /// [`LayoutError::NoCommonMarkers`] when the source shares no label with the model.
    pub fn new(
        identity: Identity,
        model: Arc<IcaModel>,
        performer: Option<usize>,
        source_labels: &Arc<[String]>,
        lowpass_s: f32,
    ) -> Result<Stream, LayoutError> {
        let map = LabelMap::new(model.labels(), source_labels)?;
        let (m, rate) = (model.components(), model.rate_hz());
        let mut stream = Stream::with_layout(identity, map, source_labels, (m, rate));
        stream.edit = EditState::for_model(&model, lowpass_s);
        stream.processor = Some(FrameProcessor::new(&model));
        stream.model = Some(model);
        stream.performer = performer;
        Ok(stream)
    }

    /// A stream without a model: its frames pass through unedited, in the source's order and
    /// under its labels, announced at `rate_hz`.
    ///
    /// # Errors
    /// [`LayoutError::NoCommonMarkers`] when the source names no marker.
    pub fn passthrough(
        identity: Identity,
        performer: Option<usize>,
        source_labels: &Arc<[String]>,
        rate_hz: f64,
    ) -> Result<Stream, LayoutError> {
        let map = LabelMap::new(source_labels, source_labels)?;
        let mut stream = Stream::with_layout(identity, map, source_labels, (0, rate_hz));
        stream.performer = performer;
        Ok(stream)
    }

    /// The buffers of a stream whose output has `map`'s markers and `m` components, at
    /// `rate_hz`; no model yet.
    fn with_layout(
        identity: Identity,
        map: LabelMap,
        source_labels: &Arc<[String]>,
        (m, rate_hz): (usize, f64),
    ) -> Stream {
        let n = map.model_to_take.len();
        Stream {
            identity,
            frames_since_labels: 0,
            processor: None,
            edit: EditState::new(0, &[], 0.0),
            map,
            source_labels: Arc::clone(source_labels),
            source_missing: vec![false; source_labels.len()],
            xyz: vec![0.0; n * 3],
            missing: vec![false; n],
            u: vec![0.0; m],
            u_in: vec![0.0; m],
            out: vec![0.0; n * 3],
            last_frame: None,
            stale_run: (0, 0),
            frames: 0,
            duplicates: 0,
            stale: 0,
            heard_sweep: 0,
            model: None,
            rate_hz,
            performer: None,
        }
    }

    /// This stream on `model` (a model swap): same source, performer, edit settings and frame
    /// order, so the next frame is neither dropped nor taken for a restart. A stream without a
    /// model rebuilt on one is edited from its next frame.
    ///
    /// # Errors
    /// As [`Stream::new`].
    pub fn rebuilt_on(&self, model: Arc<IcaModel>, lowpass_s: f32) -> Result<Stream, LayoutError> {
        let who = self.identity.clone();
        let mut fresh = Stream::new(who, model, self.performer, &self.source_labels, lowpass_s)?;
        fresh.edit.copy_settings(&self.edit);
        fresh.last_frame = self.last_frame;
        fresh.frames = self.frames;
        fresh.duplicates = self.duplicates;
        fresh.stale = self.stale;
        fresh.heard_sweep = self.heard_sweep;
        Ok(fresh)
    }

    /// The labels of [`Stream::edited`]: the model's, or the source's without a model.
    pub fn labels(&self) -> &[String] {
        match &self.model {
            Some(m) => m.labels(),
            None => &self.source_labels,
        }
    }

    /// The model's rate, or the rate given to a stream without a model.
    pub fn rate_hz(&self) -> f64 {
        self.rate_hz
    }

    /// Whether the stream runs on `model` (both `None`: neither has one).
    pub fn runs_on(&self, model: Option<&Arc<IcaModel>>) -> bool {
        same_model(self.model.as_ref(), model)
    }

    /// The components of the last processed frame, after the edit.
    pub fn components(&self) -> &[f32] {
        &self.u
    }

    /// The edited frame in model order (gaps filled by the model).
    pub fn edited(&self) -> &[f32] {
        &self.out
    }

    /// The source's labels, in the order of its frames.
    pub fn source_labels(&self) -> &[String] {
        &self.source_labels
    }

    /// The components of the last processed frame, before the edit.
    pub fn components_in(&self) -> &[f32] {
        &self.u_in
    }

    /// The last processed frame as received, in model order (markers the source lacks are 0).
    pub fn input(&self) -> &[f32] {
        &self.xyz
    }

    /// Which markers of the last frame were missing as received, model order.
    pub fn input_missing(&self) -> &[bool] {
        &self.missing
    }

    /// Which markers of the last frame the model filled (missing, or rejected as glitches;
    /// none without a model).
    pub fn filled(&self) -> &[bool] {
        self.processor.as_ref().map_or(&[], |p| p.filled())
    }

    /// The last frame number taken.
    pub fn last_frame(&self) -> Option<i32> {
        self.last_frame
    }

    /// Whether `labels` are the ones this stream was made for (the same shared list, or an
    /// equal one): a source that relabels a stream starts it over.
    pub fn has_source_labels(&self, labels: &Arc<[String]>) -> bool {
        Arc::ptr_eq(&self.source_labels, labels) || self.source_labels == *labels
    }

    /// The markers of `labels` (another model's) that this stream's source does not name.
    pub fn missing_from_source(&self, labels: &[String]) -> Vec<String> {
        labels
            .iter()
            .filter(|l| !self.source_labels.contains(l))
            .cloned()
            .collect()
    }

    /// The model's markers the source's labels do not name (always missing in this stream).
    pub fn unmatched_markers(&self) -> usize {
        self.map
            .model_to_take
            .iter()
            .filter(|t| t.is_none())
            .count()
    }
}

/// Whether two streams' models are the same (the same loaded model, or neither has one).
pub fn same_model(a: Option<&Arc<IcaModel>>, b: Option<&Arc<IcaModel>>) -> bool {
    match (a, b) {
        (Some(a), Some(b)) => Arc::ptr_eq(a, b),
        (None, None) => true,
        _ => false,
    }
}

#[cfg(test)]
mod tests;
