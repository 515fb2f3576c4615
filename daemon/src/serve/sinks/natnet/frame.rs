//! Processed frames as NatNet frames and model definitions, sans-IO: each performer stream is
//! one markerset named by the performer (the stream's name when none is configured), its
//! markers the model's labels in model order (a `<name>:` prefix, as Motive-named exports
//! carry, taken off: Motive's markerset descriptions name bare markers).
//!
//! A frame carries every stream's markerset with its latest markers (a frame of one stream
//! brings its own; a stage's performers arrive within the same capture tick), numbered by the
//! stream that just came. In it:
//! - positions in metres (emoshift works in millimetres), y up as the source sent them;
//! - a marker missing in the input stays missing: NaN in the markerset, and a labelled marker
//!   flagged occluded; a marker the model replaced (a glitch) is flagged model-solved;
//! - labelled markers with `model id << 16 | marker index` (model id: the markerset's place
//!   in the definitions, 1-based; marker index 1-based, as Motive counts);
//! - the source's frame number, timecode and subframe, and its capture time as the `f64`
//!   timestamp (seconds); the camera mid-exposure stamp is the capture time when the source's
//!   clock is UTC (the server clock is µs since the Unix epoch), else 0 (unknown, as Motive
//!   sends it for cameras without one); data-received and transmit stamps are the server
//!   clock when the frame reached the sink;
//! - the "tracked models changed" flag for [`CHANGED_FRAMES`] frames after a stream appeared,
//!   was relabelled or left (lost datagrams must not hide it).
//!
//! With `natnet_server_raw` each stream also has a `<name>_raw` markerset: its input as
//! received, in model order.

use std::sync::Arc;

use engine::pipeline::MAX_SOURCES;
use engine::{Processed, StreamKey};
use ica_core::model::IcaModel;
use protocol::natnet::{
    FrameOfData, LabeledMarker, MarkerParams, MarkersetDef, ModelDefs, MM_PER_M,
};
use protocol::CaptureClock;

/// Frames flagged "tracked models changed" after a change.
pub const CHANGED_FRAMES: u8 = 3;
/// Labelled marker flags: occluded.
const OCCLUDED: u16 = 0x01;
/// Labelled marker flags: solved by the model.
const MODEL_SOLVED: u16 = 0x04;
/// Labelled marker flags: belongs to a model.
const HAS_MODEL: u16 = 0x08;

/// One stream's latest frame.
#[derive(Debug)]
struct StreamOut {
    key: StreamKey,
    id: i32,
    name: String,
    raw_name: String,
    model: Option<Arc<IcaModel>>,
    /// The source's labels it was made with (a relabelled source makes it again).
    source_labels: (usize, usize),
    marker_names: Vec<String>,
    positions: Vec<[f32; 3]>,
    params: Vec<u16>,
    raw: Vec<[f32; 3]>,
}

/// Every stream's latest frame, the frame and the definitions built from them.
#[derive(Debug)]
pub struct Streams {
    list: Vec<StreamOut>,
    raw: bool,
    changed: u8,
    /// Bumped whenever the definitions change.
    pub generation: u64,
    /// The frame last built.
    pub frame: FrameOfData,
}

impl Streams {
    /// Streams of up to `max_markers` markers; `raw`: with their `<name>_raw` markersets.
    pub fn new(max_markers: usize, raw: bool) -> Streams {
        Streams {
            list: Vec::new(),
            raw,
            changed: 0,
            generation: 0,
            frame: FrameOfData::with_capacity(max_markers * 2, 0),
        }
    }

    /// Takes `f` as its stream's latest frame and builds the frame to send (`ticks`: the
    /// server clock now); [`Streams::generation`] tells whether the definitions changed.
    pub fn handle_frame(&mut self, f: &Processed<'_>, ticks: u64) {
        let at = self.slot(f);
        let s = &mut self.list[at];
        let output = f.output.positions();
        let missing = f.stream.input_missing();
        let filled = f.stream.filled();
        let input = f.stream.input();
        for i in 0..s.positions.len() {
            let gone = missing.get(i).copied().unwrap_or(true);
            let xyz = output.get(3 * i..3 * i + 3).unwrap_or(&[f32::NAN; 3]);
            s.positions[i] = if gone {
                [f32::NAN; 3]
            } else {
                [xyz[0] / MM_PER_M, xyz[1] / MM_PER_M, xyz[2] / MM_PER_M]
            };
            let replaced = !gone && filled.get(i).copied().unwrap_or(false);
            s.params[i] = HAS_MODEL
                | if gone { OCCLUDED } else { 0 }
                | if replaced { MODEL_SOLVED } else { 0 };
            if self.raw {
                let raw = input.get(3 * i..3 * i + 3).unwrap_or(&[f32::NAN; 3]);
                s.raw[i] = if gone {
                    [f32::NAN; 3]
                } else {
                    [raw[0] / MM_PER_M, raw[1] / MM_PER_M, raw[2] / MM_PER_M]
                };
            }
        }
        self.build(f, ticks);
        self.changed = self.changed.saturating_sub(1);
    }

    /// Streams that left: the definitions change.
    pub fn handle_gone(&mut self, gone: &[StreamKey]) {
        let before = self.list.len();
        self.list.retain(|s| !gone.contains(&s.key));
        if self.list.len() != before {
            self.changed = CHANGED_FRAMES;
            self.generation += 1;
        }
    }

    /// The model definitions: one markerset per stream (and its `_raw` one).
    pub fn defs(&self) -> ModelDefs {
        let mut markersets = Vec::with_capacity(self.list.len() * 2);
        for s in &self.list {
            markersets.push(MarkersetDef {
                name: s.name.clone(),
                marker_names: s.marker_names.clone(),
            });
            if self.raw {
                markersets.push(MarkersetDef {
                    name: s.raw_name.clone(),
                    marker_names: s.marker_names.clone(),
                });
            }
        }
        ModelDefs {
            markersets,
            ..ModelDefs::default()
        }
    }

    /// Streams now.
    pub fn len(&self) -> usize {
        self.list.len()
    }

    /// No stream yet.
    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// The slot of `f`'s stream, made (and the definitions changed) when it is new, its
    /// model swapped or its source relabelled.
    fn slot(&mut self, f: &Processed<'_>) -> usize {
        let id = f.identity().id;
        let labels = f.input_labels();
        let source_labels = (labels.as_ptr() as usize, labels.len());
        let found = self.list.iter().position(|s| s.id == id);
        if let Some(i) = found {
            let s = &self.list[i];
            if f.stream.runs_on(s.model.as_ref())
                && s.source_labels == source_labels
                && s.name == f.identity().name
            {
                return i;
            }
        }
        let name = f.identity().name.clone();
        let marker_names = f.labels().iter().map(|l| bare(&name, l)).collect();
        let n = f.labels().len();
        let fresh = StreamOut {
            key: f.key,
            id,
            raw_name: format!("{name}_raw"),
            name,
            model: f.stream.model.clone(),
            source_labels,
            marker_names,
            positions: vec![[f32::NAN; 3]; n],
            params: vec![0; n],
            raw: vec![[f32::NAN; 3]; if self.raw { n } else { 0 }],
        };
        self.changed = CHANGED_FRAMES;
        self.generation += 1;
        match found {
            Some(i) => {
                self.list[i] = fresh;
                i
            }
            None => {
                if self.list.len() >= MAX_SOURCES {
                    self.list.remove(0);
                }
                self.list.push(fresh);
                self.list.len() - 1
            }
        }
    }

    /// The frame of every stream's latest markers, numbered and timed by `f`.
    fn build(&mut self, f: &Processed<'_>, ticks: u64) {
        let frame = &mut self.frame;
        frame.clear();
        frame.frame_number = f.frame_number();
        for (k, s) in self.list.iter().enumerate() {
            frame.push_markerset(&s.name, &s.positions);
            let model = (k as u32 + 1) << 16;
            for (i, (p, &params)) in s.positions.iter().zip(&s.params).enumerate() {
                frame.labeled_markers.push(LabeledMarker {
                    id: model | (i as u32 + 1),
                    position: *p,
                    size: 0.0,
                    params: MarkerParams(params),
                    residual: 0.0,
                });
            }
        }
        if self.raw {
            for s in &self.list {
                frame.push_markerset(&s.raw_name, &s.raw);
            }
        }
        let capture_us = f.output.header().capture_time_us;
        if let Some(t) = f.time.timecode {
            frame.timecode = t.packed();
            frame.timecode_subframe = t.subframe;
        }
        frame.timestamp = capture_us as f64 / 1e6;
        frame.camera_mid_exposure = match f.time.clock {
            CaptureClock::Utc => u64::try_from(capture_us).unwrap_or(0),
            CaptureClock::Source => 0,
        };
        frame.camera_data_received = ticks;
        frame.transmit = ticks;
        frame.params.0 = if self.changed > 0 { 0x02 } else { 0 };
    }
}

/// `label` without a leading `<name>:`.
fn bare(name: &str, label: &str) -> String {
    label
        .strip_prefix(name)
        .and_then(|rest| rest.strip_prefix(':'))
        .filter(|rest| !rest.is_empty())
        .unwrap_or(label)
        .to_string()
}

#[cfg(test)]
mod tests;
