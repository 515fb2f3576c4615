//! Processed frames as one QTM labelled-marker list, sans-IO: QTM has no marker sets, so every
//! performer stream's markers go one after another, labelled by the model's labels (prefixed
//! `<performer>_` when there are several streams, which a QTM source's `qtm_performers`
//! prefixes take apart again). A frame of one stream brings its own markers; the others keep
//! their latest. Markers missing in the input are NaN, as QTM sends them. The frame number,
//! capture time (µs) and SMPTE or IRIG timecode are the source's.

use std::sync::Arc;

use engine::pipeline::MAX_SOURCES;
use engine::{Processed, StreamKey};
use ica_core::model::IcaModel;
use protocol::qtm::{DataFrame, Timecode};

/// One stream's place in the list.
#[derive(Debug)]
struct Slot {
    key: StreamKey,
    id: i32,
    name: String,
    model: Option<Arc<IcaModel>>,
    /// The source's labels it was made with (a relabelled source makes it again).
    source_labels: (usize, usize),
    labels: Vec<String>,
    start: usize,
}

/// Every stream's latest markers, as one list.
#[derive(Debug, Default)]
pub struct Layout {
    slots: Vec<Slot>,
    /// The labels, in marker order.
    pub labels: Vec<String>,
    positions: Vec<f32>,
    /// Bumped whenever the labels change.
    pub generation: u64,
    /// The latest frame's number.
    pub frame_number: u32,
    timestamp_us: i64,
    timecode: Option<Timecode>,
    /// The latest stream's rate.
    pub rate_hz: f64,
    /// Whether any frame came yet.
    pub has_frame: bool,
}

impl Layout {
    /// Takes `f` as its stream's latest frame.
    pub fn handle_frame(&mut self, f: &Processed<'_>) {
        let at = self.slot(f);
        let start = self.slots[at].start;
        let n = self.slots[at].labels.len();
        let output = f.output.positions();
        let missing = f.stream.input_missing();
        for i in 0..n {
            let gone = missing.get(i).copied().unwrap_or(true);
            let xyz = output.get(3 * i..3 * i + 3).unwrap_or(&[f32::NAN; 3]);
            let to = &mut self.positions[3 * (start + i)..3 * (start + i) + 3];
            for (t, v) in to.iter_mut().zip(xyz) {
                *t = if gone { f32::NAN } else { *v };
            }
        }
        let header = f.output.header();
        self.frame_number = header.frame_number as u32;
        self.timestamp_us = header.capture_time_us;
        self.timecode = Timecode::from_frame_time(f.time);
        self.rate_hz = f.rate_hz();
        self.has_frame = true;
    }

    /// Streams that left: the labels change.
    pub fn handle_gone(&mut self, gone: &[StreamKey]) {
        let before = self.slots.len();
        self.slots.retain(|s| !gone.contains(&s.key));
        if self.slots.len() != before {
            self.relayout();
        }
    }

    /// The latest frame, to encode.
    pub fn frame(&self) -> DataFrame<'_> {
        DataFrame {
            timestamp_us: self.timestamp_us,
            frame_number: self.frame_number,
            positions: &self.positions,
            timecode: self.timecode,
        }
    }

    /// The slot of `f`'s stream, made (and the labels changed) when it is new, its model
    /// swapped or its source relabelled.
    fn slot(&mut self, f: &Processed<'_>) -> usize {
        let id = f.identity().id;
        let labels = f.input_labels();
        let source_labels = (labels.as_ptr() as usize, labels.len());
        let found = self.slots.iter().position(|s| s.id == id);
        if let Some(i) = found {
            let s = &self.slots[i];
            if f.stream.runs_on(s.model.as_ref())
                && s.source_labels == source_labels
                && s.name == f.identity().name
            {
                return i;
            }
        }
        let fresh = Slot {
            key: f.key,
            id,
            name: f.identity().name.clone(),
            model: f.stream.model.clone(),
            source_labels,
            labels: f.labels().to_vec(),
            start: 0,
        };
        let at = match found {
            Some(i) => {
                self.slots[i] = fresh;
                i
            }
            None => {
                if self.slots.len() >= MAX_SOURCES {
                    self.slots.remove(0);
                }
                self.slots.push(fresh);
                self.slots.len() - 1
            }
        };
        self.relayout();
        at
    }

    /// The labels and places again, every marker missing until its stream's next frame.
    fn relayout(&mut self) {
        let several = self.slots.len() > 1;
        self.labels.clear();
        for s in &mut self.slots {
            s.start = self.labels.len();
            for l in &s.labels {
                self.labels.push(if several {
                    format!("{}_{l}", s.name)
                } else {
                    l.clone()
                });
            }
        }
        self.positions.clear();
        self.positions.resize(self.labels.len() * 3, f32::NAN);
        self.generation += 1;
    }
}
