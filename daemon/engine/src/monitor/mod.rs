//! The monitor tap: a decimated copy of each stream's frames for the monitor page. Sans-IO:
//! the caller gives the time (`now_us`, any monotonic microsecond clock) and the [`Stream`]
//! whose frame was just processed; the tap decides whether that stream is due (at most
//! `max_hz` per stream, on an accumulating schedule, so the average never exceeds it) and
//! copies the frame into a [`Snapshot`] it owns.
//!
//! Call order, on the processing thread after each datagram: [`MonitorTap::handle_stream`] for
//! the stream whose frame went out; when it returns a snapshot, the caller publishes it (the
//! shell swaps it with the one it published last, so buffers are reused, not reallocated) and
//! calls nothing else. Filling allocates only while a snapshot's buffers grow to the largest
//! stream seen (a new stream, a bigger model); warm, the tap allocates nothing
//! (daemon/tests/it/pipeline_alloc.rs counts it).

use std::sync::Arc;

use ica_core::model::IcaModel;

use super::pipeline::MAX_SOURCES;
use super::Stream;

/// Default rate of the decimated feed per stream (the page draws at most this often).
pub const DEFAULT_MONITOR_HZ: f64 = 30.0;

/// Marker flag: missing in the frame as received (or never named by the source).
pub const FLAG_MISSING: u8 = 1;
/// Marker flag: filled by the model in the output (missing, or rejected as a glitch).
pub const FLAG_FILLED: u8 = 2;

/// One stream's frame as the monitor page draws it; buffers in model marker order.
#[derive(Debug, Clone, Default)]
pub struct Snapshot {
    /// The tap's count of snapshots taken, 1 for the first (0: never filled).
    pub seq: u64,
    /// When it was taken, on the caller's clock.
    pub at_us: u64,
    /// Stream id (as `/emoshift/stream` carries it).
    pub stream_id: i32,
    /// Stream name.
    pub name: String,
    /// Frame number.
    pub frame_number: i32,
    /// The stream's model (its labels, roles and emotion space); `None` for a stream passed
    /// through without one (markers in the source's order, no components).
    pub model: Option<Arc<IcaModel>>,
    /// Positions as received, x y z per marker (0 where missing).
    pub input: Vec<f32>,
    /// Edited positions, x y z per marker (gaps filled by the model).
    pub output: Vec<f32>,
    /// Per marker: [`FLAG_MISSING`], [`FLAG_FILLED`].
    pub flags: Vec<u8>,
    /// Components before the edit.
    pub u_in: Vec<f32>,
    /// Components after the edit.
    pub u_out: Vec<f32>,
    /// Target emotion as the engine applies it (empty before one is set).
    pub target: String,
    /// Amount now, mid-glide included.
    pub amount: f32,
    /// Amount glided to.
    pub amount_goal: f32,
    /// Ramp of new settings, seconds.
    pub ramp_s: f32,
    /// Bypass set.
    pub bypass: bool,
    /// Frames taken in order.
    pub frames: u64,
    /// Duplicate frame numbers dropped.
    pub duplicates: u64,
    /// Older frames dropped.
    pub stale: u64,
}

impl Snapshot {
    /// Copies the stream's last processed frame and state in (no allocation once the buffers
    /// have the stream's size).
    pub fn fill_from(&mut self, stream: &Stream) {
        self.stream_id = stream.identity.id;
        self.name.clear();
        self.name.push_str(&stream.identity.name);
        self.frame_number = stream.last_frame().unwrap_or(0);
        if !stream.runs_on(self.model.as_ref()) {
            self.model.clone_from(&stream.model);
        }
        copy(&mut self.input, stream.input());
        copy(&mut self.output, stream.edited());
        copy(&mut self.u_in, stream.components_in());
        copy(&mut self.u_out, stream.components());
        self.flags.clear();
        let (missing, filled) = (stream.input_missing(), stream.filled());
        for (i, &gone) in missing.iter().enumerate() {
            // Without a model nothing is filled: a missing marker stays missing.
            let filled = filled
                .get(i)
                .copied()
                .unwrap_or(gone && stream.model.is_some());
            self.flags
                .push((u8::from(gone) * FLAG_MISSING) | (u8::from(filled) * FLAG_FILLED));
        }
        let edit = &stream.edit;
        self.target.clear();
        self.target.push_str(edit.target());
        self.amount = edit.amount();
        self.amount_goal = edit.amount_goal();
        self.ramp_s = edit.ramp_s();
        self.bypass = edit.bypassed();
        (self.frames, self.duplicates, self.stale) =
            (stream.frames, stream.duplicates, stream.stale);
    }
}

fn copy(to: &mut Vec<f32>, from: &[f32]) {
    to.clear();
    to.extend_from_slice(from);
}

/// When each stream is next due.
#[derive(Debug, Clone)]
struct Due {
    stream_id: i32,
    next_us: u64,
}

/// The decimating tap. See the module docs for the call order.
#[derive(Debug, Clone)]
pub struct MonitorTap {
    period_us: u64,
    due: Vec<Due>,
    ready: Snapshot,
    seq: u64,
}

impl MonitorTap {
    /// A tap giving each stream at most `max_hz` snapshots a second (clamped to 1..=120).
    pub fn new(max_hz: f64) -> MonitorTap {
        let hz = if max_hz.is_finite() {
            max_hz.clamp(1.0, 120.0)
        } else {
            DEFAULT_MONITOR_HZ
        };
        MonitorTap {
            period_us: (1e6 / hz).round() as u64,
            due: Vec::with_capacity(MAX_SOURCES),
            ready: Snapshot::default(),
            seq: 0,
        }
    }

    /// Whether stream `stream_id` is due at `now_us`; if so, its next turn is one period
    /// later (or one period from now, after a pause), so the average rate stays at most
    /// `max_hz` however the frames fall.
    pub fn due(&mut self, stream_id: i32, now_us: u64) -> bool {
        let period = self.period_us;
        let slot = match self.due.iter().position(|d| d.stream_id == stream_id) {
            Some(i) => &mut self.due[i],
            None => {
                if self.due.len() >= MAX_SOURCES {
                    // Forget the stream longest without a snapshot (most likely gone).
                    let oldest = (0..self.due.len())
                        .min_by_key(|&i| self.due[i].next_us)
                        .unwrap_or(0);
                    self.due.swap_remove(oldest);
                }
                self.due.push(Due {
                    stream_id,
                    next_us: now_us,
                });
                self.due.last_mut().expect("just pushed")
            }
        };
        // A frame up to an eighth of a period early counts as on time: a 120 Hz source's
        // jitter then gives every 4th frame rather than a 4-5-4-5 pattern. The schedule still
        // advances by whole periods, so the average stays at `max_hz`.
        if now_us + period / 8 < slot.next_us {
            return false;
        }
        slot.next_us += period;
        if slot.next_us <= now_us {
            slot.next_us = now_us + period;
        }
        true
    }

    /// Takes `stream`'s last processed frame when the stream is due at `now_us`: the filled
    /// snapshot, for the caller to publish (swapping in the one it published before is how
    /// buffers are reused).
    pub fn handle_stream(&mut self, now_us: u64, stream: &Stream) -> Option<&mut Snapshot> {
        if !self.due(stream.identity.id, now_us) {
            return None;
        }
        self.seq += 1;
        self.ready.fill_from(stream);
        self.ready.seq = self.seq;
        self.ready.at_us = now_us;
        Some(&mut self.ready)
    }
}

#[cfg(test)]
mod tests;
