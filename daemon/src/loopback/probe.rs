//! What a client sees of the emotion edit: each received frame's number, arrival, emotion
//! state and its markers' coordinates on the model's emotion axes ([`emotion_probe`]); the
//! latency from a source's send to that arrival ([`latency_us`]); and the sweep in windows of
//! means ([`windows`]). The demo prints them; a test can assert on them.

use std::collections::HashMap;
use std::time::Instant;

use hdrhistogram::Histogram;
use ica_core::model::{IcaModel, SpaceTarget};

use super::receiver::Received;
use crate::serve::stats::Stats;

/// One received frame as the probe saw it.
#[derive(Debug, Clone)]
pub struct Seen {
    /// The frame number.
    pub number: i32,
    /// When it arrived.
    pub at: Instant,
    /// The emotion state sent with it: target and amount.
    pub target: String,
    /// How far towards the target.
    pub amount: f32,
    /// Its markers projected onto the model's emotion axes (`None`: a frame with gaps, or a
    /// model without an emotion space).
    pub emotion: Option<Vec<f32>>,
}

/// A sink for [`super::Receiver::collect`] of the compact profile that projects every
/// received frame onto `model`'s emotion axes.
pub fn emotion_probe(model: &IcaModel) -> impl FnMut(&mut Vec<Seen>, &Received<'_>) + Send {
    let mut processor = engine::frame::FrameProcessor::new(model);
    let (markers, mut u) = (model.markers(), vec![0.0f32; model.components()]);
    let space = SpaceTarget::new(model.emotion(), model.components());
    let mut missing = Vec::with_capacity(markers);
    move |seen, r| {
        let Some((header, frame)) = r.frame else {
            return;
        };
        missing.clear();
        missing.extend((0..frame.marker_count()).map(|i| frame.is_missing(i)));
        let complete = space.dims() > 0 && missing.len() == markers;
        let emotion = complete
            .then(|| processor.project(frame.positions(), &missing, &mut u).ok())
            .flatten()
            .map(|_| {
                let mut at = vec![0.0f32; space.dims()];
                space.coordinates_into(&u, &mut at);
                at
            });
        let state = r.state.as_ref();
        seen.push(Seen {
            number: header.frame_number,
            at: r.at,
            target: state.map_or_else(String::new, |s| s.target.to_string()),
            amount: state.map_or(0.0, |s| s.amount),
            emotion,
        });
    }
}

/// Send-to-arrival latency of every seen frame whose send time is known, µs.
pub fn latency_us(sent: &HashMap<i64, Instant>, seen: &[Seen]) -> Histogram<u64> {
    let mut h = Stats::histogram();
    for s in seen {
        if let Some(at) = sent.get(&i64::from(s.number)) {
            Stats::record(&mut h, s.at.duration_since(*at).as_micros() as u64);
        }
    }
    h
}

/// The frames seen in one window of time.
#[derive(Debug, Clone)]
pub struct Window {
    /// Its start, seconds after the origin.
    pub from_s: f64,
    /// The emotion state of its last frame.
    pub target: String,
    /// Its amount.
    pub amount: f32,
    /// The mean emotion coordinates of its frames that had them.
    pub emotion: Vec<f32>,
}

/// `seen` in windows of `width_s` seconds from `origin` (the state is its last projected
/// frame's); windows without a projected frame are left out.
pub fn windows(seen: &[Seen], origin: Instant, width_s: f64) -> Vec<Window> {
    let mut out: Vec<(Window, usize)> = Vec::new();
    for s in seen {
        let Some(values) = &s.emotion else { continue };
        let t = s.at.saturating_duration_since(origin).as_secs_f64();
        let from_s = (t / width_s).floor() * width_s;
        if out.last().is_none_or(|(w, _)| w.from_s != from_s) {
            let emotion = vec![0.0; values.len()];
            let (target, amount) = (String::new(), 0.0);
            out.push((
                Window {
                    from_s,
                    target,
                    amount,
                    emotion,
                },
                0,
            ));
        }
        if let Some((w, n)) = out.last_mut() {
            w.target.clone_from(&s.target);
            w.amount = s.amount;
            w.emotion.iter_mut().zip(values).for_each(|(a, v)| *a += v);
            *n += 1;
        }
    }
    out.into_iter()
        .map(|(mut w, n)| {
            w.emotion.iter_mut().for_each(|v| *v /= n as f32);
            w
        })
        .collect()
}
