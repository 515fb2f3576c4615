//! The [`Pipeline`]: the engine's one entry point (the path is drawn in [`crate::engine`]). It
//! owns every buffer (sized at construction, and per stream when the stream is made).
//!
//! Call order: [`Pipeline::handle_datagram`] per received datagram, which calls `emit` once
//! per processed frame with the encoded bytes; [`Pipeline::handle_edit`] and
//! [`Pipeline::set_model`] between datagrams (a frame boundary).

use core::net::SocketAddr;
use std::collections::HashMap;
use std::sync::Arc;

use ica_core::model::IcaModel;
use protocol::{
    decode_frame_into, decode_labels, decode_timecode, messages, Address, Control, DecodeError,
    FrameBuf, FrameTime, LayoutBook, LayoutChange, Limits, Profile,
};

use crate::engine::edit_state::{EditRefused, EditState};
use crate::engine::stream::Identity;
use crate::engine::streams::{Performer, StreamKey, StreamStatus, Streams};
use crate::engine::Counters;

mod encode;
mod natnet;
mod run;
mod setup;

use encode::Outputs;
pub use encode::{profile_bit, ProfileMask};
pub use setup::apply_edit;

/// A source's datagram refused with a reason it should hear (`/emoshift/error` on the frame
/// socket); the shell sends it, rate-limited.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Refusal {
    /// The source.
    pub to: SocketAddr,
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

fn describe_mismatch(streams: &[(String, Vec<String>)]) -> String {
    let each: Vec<String> = streams
        .iter()
        .map(|(name, missing)| {
            let shown: Vec<&str> = missing.iter().take(8).map(String::as_str).collect();
            let more = missing.len().saturating_sub(shown.len());
            let more = if more > 0 {
                format!(" and {more} more")
            } else {
                String::new()
            };
            format!(
                "stream {name} lacks {} of its markers: {}{more}",
                missing.len(),
                shown.join(", ")
            )
        })
        .collect();
    format!(
        "the model does not fit the running streams, kept the old one: {}",
        each.join("; ")
    )
}

/// Sources tracked for labels, and streams, at most (bounds memory against spoofed senders).
pub const MAX_SOURCES: usize = 64;
/// Sweeps ([`Pipeline::forget_quiet_sources`]) an OSC source may stay silent through: at the
/// next it is forgotten (its layouts and streams go, and its slot among [`MAX_SOURCES`] is free
/// again). A source that comes back is taken again from its next labels (sent every second).
pub const QUIET_SWEEPS: u64 = 3;
/// How often the service sweeps, seconds (for the refusal's words; the shell owns the clock).
pub const SWEEP_SECONDS: u64 = 10;

/// One processed frame, borrowed from the pipeline's buffers.
#[derive(Debug)]
pub struct Emitted<'a> {
    /// The stream.
    pub key: StreamKey,
    /// Who the stream is to subscribers.
    pub identity: &'a Identity,
    /// The stream's `/mocap/labels` (model order, layout id = stream id).
    pub labels_msg: &'a [u8],
    /// The labels go to every subscriber with this frame (the stream's first, then once a
    /// second); a subscriber new to the stream gets them with its first frame regardless.
    pub labels_due: bool,
    /// Frame number.
    pub frame_number: i32,
    /// Frame numbers since the stream's previous processed frame: 1 when none was lost or
    /// dropped on the way (and for a stream's first frame or a restart).
    pub frames_since_last: u32,
    /// Compact bundle (empty when not wanted).
    pub compact: &'a [u8],
    /// Flat-split parts, concatenated; see `part_ends`.
    pub parts: &'a [u8],
    /// End offset of each part in `parts`.
    pub part_ends: &'a [usize],
    /// Components message (empty when not wanted).
    pub components: &'a [u8],
    /// Edited positions in model order (gaps filled by the model).
    pub xyz: &'a [f32],
    /// The frame as received: every marker the source sent, with its gaps.
    pub input: &'a FrameBuf,
    /// The source's labels of `input`.
    pub input_labels: &'a [String],
    /// The stream's model labels.
    pub labels: &'a [String],
    /// The stream's model rate.
    pub rate_hz: f64,
    /// The source's time of the frame: SMPTE timecode and capture clock (the capture time is
    /// `input.header().capture_time_us`).
    pub time: &'a FrameTime,
}

/// Pipeline settings.
#[derive(Debug, Clone)]
pub struct PipelineConfig {
    /// Low-pass window of the emotion edit (seconds).
    pub lowpass_s: f32,
    /// Largest frame accepted (markers).
    pub max_markers: usize,
}

impl Default for PipelineConfig {
    fn default() -> Self {
        PipelineConfig {
            lowpass_s: crate::engine::edit_state::DEFAULT_LOWPASS_S,
            max_markers: 1_000,
        }
    }
}

/// The processing path. See the module docs for the call order.
#[derive(Debug)]
pub struct Pipeline {
    config: PipelineConfig,
    model: Arc<IcaModel>,
    performers: Vec<Performer>,
    layouts: LayoutBook<SocketAddr>,
    streams: Streams,
    /// Settings of the default model's streams, copied into new streams.
    template: EditState,
    limits: Limits,
    frame_in: FrameBuf,
    frame_out: FrameBuf,
    /// The time of the frame being handled (from the datagram's `/mocap/timecode`).
    time_in: FrameTime,
    /// NatNet frames decoded here, reused.
    natnet: natnet::NatNetInput,
    outputs: Outputs,
    wanted: ProfileMask,
    /// The last refusal the source should hear, taken by the shell after each datagram.
    refusal: Option<Refusal>,
    /// Per OSC source the layout book holds, the sweep it was last heard in.
    heard: HashMap<SocketAddr, u64>,
    /// Sweeps so far.
    sweeps: u64,
    /// Counters, read by the caller after each batch.
    pub counters: Counters,
}

impl Pipeline {
    /// A pipeline over `model`, with optional named performers.
    pub fn new(model: Arc<IcaModel>, performers: Vec<Performer>, config: PipelineConfig) -> Self {
        let template = EditState::for_model(&model, config.lowpass_s);
        Pipeline {
            layouts: LayoutBook::new(MAX_SOURCES),
            streams: Streams::new(MAX_SOURCES),
            limits: Limits::default(),
            frame_in: FrameBuf::with_max_markers(config.max_markers),
            frame_out: FrameBuf::with_max_markers(config.max_markers),
            time_in: FrameTime::default(),
            natnet: natnet::NatNetInput::new(config.max_markers),
            outputs: Outputs::new(config.max_markers),
            wanted: profile_bit(Profile::Compact),
            refusal: None,
            heard: HashMap::with_capacity(MAX_SOURCES),
            sweeps: 0,
            counters: Counters::default(),
            template,
            model,
            performers,
            config,
        }
    }

    /// Forgets the OSC sources heard last before the last [`QUIET_SWEEPS`] calls (the shell
    /// calls this every [`SWEEP_SECONDS`]): their layouts, their streams and their slot. Without it a
    /// stage whose sources restart from new ports (a bridge or Motive restarted) fills the
    /// [`MAX_SOURCES`] slots with dead sources, and the next one is never taken. Returns the
    /// sources forgotten.
    pub fn forget_quiet_sources(&mut self) -> Vec<SocketAddr> {
        self.sweeps += 1;
        let sweeps = self.sweeps;
        let quiet: Vec<SocketAddr> = self
            .heard
            .iter()
            .filter(|&(_, &last)| last + QUIET_SWEEPS < sweeps)
            .map(|(&peer, _)| peer)
            .collect();
        for peer in &quiet {
            self.heard.remove(peer);
            self.layouts.forget(peer);
            self.streams.forget_source(*peer);
        }
        quiet
    }

    /// The refusal of the last datagram, if it was refused with a reason for its source.
    pub fn take_refusal(&mut self) -> Option<Refusal> {
        self.refusal.take()
    }

    /// Sets which profiles are encoded (the subscribers' profiles).
    pub fn set_wanted(&mut self, wanted: ProfileMask) {
        self.wanted = wanted;
    }

    /// Streams now.
    pub fn stream_count(&self) -> usize {
        self.streams.len()
    }

    /// The stream of `key`, to read between datagrams (the monitor tap).
    pub fn stream(&self, key: &StreamKey) -> Option<&crate::engine::Stream> {
        self.streams.get(key)
    }

    /// Each stream's counters.
    pub fn stream_status(&self) -> Vec<StreamStatus> {
        self.streams.status(&self.performers)
    }

    /// Whether `model` can replace the default model: every stream running on the default
    /// model must name all of `model`'s markers, or it would be left with markers it never
    /// sees (or none at all).
    ///
    /// # Errors
    /// The streams it does not fit and the markers each lacks.
    pub fn check_model(&self, model: &IcaModel) -> Result<(), ModelMismatch> {
        let mut streams = Vec::new();
        for (_, stream) in self.streams.iter() {
            if !Arc::ptr_eq(&stream.model, &self.model) {
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
    /// [`Pipeline::check_model`] first: a stream it does not fit keeps the old model.
    pub fn set_model(&mut self, model: Arc<IcaModel>) {
        let mut template = EditState::for_model(&model, self.config.lowpass_s);
        template.copy_settings(&self.template);
        self.template = template;
        let old = std::mem::replace(&mut self.model, model);
        for (_, stream) in self.streams.iter_mut() {
            if !Arc::ptr_eq(&stream.model, &old) {
                continue;
            }
            // A stream whose labels share nothing with the new model keeps the old one.
            if let Ok(fresh) = stream.rebuilt_on(Arc::clone(&self.model), self.config.lowpass_s) {
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
    pub fn handle_edit(&mut self, control: &Control) -> Result<(), EditRefused> {
        let model = Arc::clone(&self.model);
        apply_edit(&mut self.template, &model, control)?;
        for (_, stream) in self.streams.iter_mut() {
            let m = Arc::clone(&stream.model);
            let _ = apply_edit(&mut stream.edit, &m, control);
        }
        Ok(())
    }

    /// Handles one received datagram; `emit` is called once per processed frame. A
    /// `/mocap/timecode` anywhere in the datagram is the time of its `/mocap/frame`.
    pub fn handle_datagram(
        &mut self,
        peer: SocketAddr,
        datagram: &[u8],
        emit: &mut dyn FnMut(&Emitted<'_>),
    ) {
        let msgs = match messages(datagram, &self.limits) {
            Ok(m) => m,
            Err(e) => {
                self.counters.bad_packet(e.kind());
                return;
            }
        };
        self.time_in = FrameTime::default();
        for msg in msgs.clone() {
            if Address::parse(msg.address) == Some(Address::Timecode) {
                match decode_timecode(msg.bytes) {
                    Ok(t) => self.time_in = t,
                    // The frame still goes through, without a time.
                    Err(e) => self.counters.bad_packet(e.kind()),
                }
            }
        }
        for msg in msgs {
            match Address::parse(msg.address) {
                Some(Address::Frame) => self.handle_frame(peer, msg.bytes, emit),
                Some(Address::Labels) => self.handle_labels(peer, msg.bytes),
                Some(Address::Timecode) => {}
                _ => self
                    .counters
                    .bad_packet(protocol::DecodeErrorKind::UnknownAddress),
            }
        }
    }

    fn handle_labels(&mut self, peer: SocketAddr, bytes: &[u8]) {
        match decode_labels(bytes) {
            Ok(labels) => {
                let id = labels.layout_id;
                self.counters.labels_in += 1;
                match self.layouts.handle_labels(&peer, labels) {
                    LayoutChange::Replaced | LayoutChange::Added => {
                        self.streams.forget(peer, id);
                    }
                    LayoutChange::Unchanged => {}
                    LayoutChange::Rejected => {
                        self.counters.labels_refused += 1;
                        let why = format!(
                            "the daemon already takes {MAX_SOURCES} sources; a source silent for {} s is forgotten, which makes room",
                            QUIET_SWEEPS * SWEEP_SECONDS
                        );
                        self.refusal = Some(Refusal { to: peer, why });
                        return;
                    }
                }
                self.heard.insert(peer, self.sweeps);
            }
            Err(e @ DecodeError::DuplicateLabel { index }) => {
                // A layout whose names repeat maps no frame; the last good one stays.
                self.counters.bad_packet(e.kind());
                self.counters.labels_refused += 1;
                let why = format!("the marker name at argument {index} is named twice");
                self.refusal = Some(Refusal { to: peer, why });
            }
            Err(e) => self.counters.bad_packet(e.kind()),
        }
    }

    /// Steps 3 to 7 of the frame's path: decode, layout, stream, [`Stream::process`],
    /// encode, emit.
    ///
    /// [`Stream::process`]: crate::engine::Stream::process
    fn handle_frame(&mut self, peer: SocketAddr, bytes: &[u8], emit: &mut dyn FnMut(&Emitted<'_>)) {
        let header = match decode_frame_into(bytes, &mut self.frame_in) {
            Ok(h) => h,
            Err(e) => return self.counters.bad_packet(e.kind()),
        };
        self.counters.frames_in += 1;
        let Some(labels) = self.layouts.layout_for(&peer, header.marker_count) else {
            return self.counters.dropped_no_layout += 1;
        };
        // An existing key: no allocation (the map holds at most MAX_SOURCES, reserved).
        self.heard.insert(peer, self.sweeps);
        let key = StreamKey {
            source: peer,
            layout_id: labels.layout_id,
        };
        let unmatched = self.counters.dropped_unmatched;
        run::frame_step(run::step!(self), key, (&labels.names, None), &header, emit);
        if self.counters.dropped_unmatched > unmatched {
            self.refusal = Some(Refusal {
                to: peer,
                why: self.why_no_stream(peer, header.marker_count),
            });
        }
    }

    /// Why a source's frame made no stream: the stream table is full, or its markers are none
    /// of the model's.
    fn why_no_stream(&self, peer: SocketAddr, marker_count: usize) -> String {
        if self.streams.len() >= MAX_SOURCES {
            return format!("the daemon already runs {MAX_SOURCES} streams");
        }
        let names = self
            .layouts
            .layout_for(&peer, marker_count)
            .map(|l| l.names.as_slice())
            .unwrap_or_default();
        let shown: Vec<&str> = names.iter().take(4).map(String::as_str).collect();
        let more = names.len().saturating_sub(shown.len());
        format!(
            "none of its {} markers ({}{}) is a marker of the model, whose markers start {}",
            names.len(),
            shown.join(", "),
            if more > 0 {
                format!(" and {more} more")
            } else {
                String::new()
            },
            self.model
                .labels()
                .iter()
                .take(4)
                .cloned()
                .collect::<Vec<_>>()
                .join(", ")
        )
    }
}

#[cfg(test)]
#[path = "tests.rs"]
pub(crate) mod tests;
