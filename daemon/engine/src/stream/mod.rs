//! One stream: a source's frames of one layout, with its own frame order, edit state,
//! low-pass state and per-frame buffers, processed by [`Stream::process`].

use std::sync::Arc;

use ica_core::model::IcaModel;
use protocol::{FrameBuf, FrameHeader, StreamTag, MAX_STREAM_NAME_BYTES};

use super::edit_state::EditState;
use super::frame::FrameProcessor;
use super::layout::{LabelMap, LayoutError};
use super::Counters;

mod order;
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
    /// The model used.
    pub model: Arc<IcaModel>,
    /// Performer index, if a performer owns the stream.
    pub performer: Option<usize>,
    /// The live edit.
    pub edit: EditState,
    /// The source's labels (shared with the source), to build the stream again on another
    /// model and to notice the source relabelling it.
    source_labels: Arc<[String]>,
    processor: FrameProcessor,
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
        let n = model.markers();
        let m = model.components();
        Ok(Stream {
            identity,
            frames_since_labels: 0,
            processor: FrameProcessor::new(&model),
            edit: EditState::for_model(&model, lowpass_s),
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
            model,
            performer,
        })
    }

    /// This stream on `model` (a model swap): same source, performer, edit settings and frame
    /// order, so the next frame is neither dropped nor taken for a restart.
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

    /// Which markers of the last frame the model filled (missing, or rejected as glitches).
    pub fn filled(&self) -> &[bool] {
        self.processor.filled()
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

    /// Takes one received frame through the stream into `output`: order check, markers into
    /// model order, projection (masked where markers are missing), the live edit, and (when
    /// `output` is `Some`: a sink reads the markers) resynthesis with the head pose put back.
    /// `None` when the frame is dropped (counted in `counters`).
    pub fn process(
        &mut self,
        header: &FrameHeader,
        input: &FrameBuf,
        output: Option<&mut FrameBuf>,
        counters: &mut Counters,
    ) -> Option<Outcome> {
        let frames = match self.check_order(header.frame_number) {
            Order::Next { frames } => frames,
            Order::Restart => {
                counters.restarts += 1;
                1
            }
            Order::Duplicate => {
                counters.dropped_duplicate += 1;
                return None;
            }
            Order::Stale => {
                counters.dropped_stale += 1;
                return None;
            }
        };
        self.gather(header, input);
        counters.missing_markers += self.missing.iter().filter(|&&m| m).count() as u64;
        let Ok(prepared) = self
            .processor
            .project(&self.xyz, &self.missing, &mut self.u)
        else {
            counters.frame_errors += 1;
            return None;
        };
        counters.glitches += prepared.glitches as u64;
        let rate = self.model.rate_hz();
        // A gap of many frames moves the glides by at most a second.
        let dt = (f64::from(frames.min(rate.max(1.0) as u32)) / rate) as f32;
        self.u_in.copy_from_slice(&self.u);
        self.edit.apply(dt, &mut self.u);
        if let Some(output) = output {
            let (pose, held) = (prepared.pose.as_ref(), prepared.status.held);
            if !self.resynthesise(header, pose, held, output) {
                counters.frame_errors += 1;
                return None;
            }
        }
        let labels_due =
            self.frames_since_labels == 0 || f64::from(self.frames_since_labels) >= rate;
        self.frames_since_labels = if labels_due {
            1
        } else {
            self.frames_since_labels + 1
        };
        Some(Outcome {
            frames_since_last: frames,
            labels_due,
        })
    }

    /// The edited components back to markers, into `self.out` and `output`; a frame too
    /// occluded to estimate (`held`) goes out as received instead. `false` when the processor
    /// or the frame refused (an internal invariant).
    fn resynthesise(
        &mut self,
        header: &FrameHeader,
        pose: Option<&ica_core::stabilise::Pose>,
        held: bool,
        output: &mut FrameBuf,
    ) -> bool {
        let resynthesised = self.processor.resynthesise(pose, &self.u, &mut self.out);
        if held {
            // Too few markers to estimate the face: what was seen goes out as received, the
            // rest as missing, rather than the last estimate passed off as data.
            for ((out, xyz), &gone) in self
                .out
                .chunks_exact_mut(3)
                .zip(self.xyz.chunks_exact(3))
                .zip(&self.missing)
            {
                if gone {
                    out.fill(f32::NAN);
                } else {
                    out.copy_from_slice(xyz);
                }
            }
        }
        resynthesised.is_ok()
            && output
                .set_frame(header.frame_number, header.capture_time_us, &self.out)
                .is_ok()
    }

    /// The input's markers into model order, with their missing flags.
    fn gather(&mut self, header: &FrameHeader, input: &FrameBuf) {
        if header.missing_count == 0 {
            self.map
                .gather_present_into(input.positions(), &mut self.xyz, &mut self.missing);
        } else {
            for (i, m) in self.source_missing.iter_mut().enumerate() {
                *m = input.is_missing(i);
            }
            let (xyz, missing) = (&mut self.xyz, &mut self.missing);
            self.map
                .gather_into(input.positions(), &self.source_missing, xyz, missing);
        }
    }
}

#[cfg(test)]
mod tests;
