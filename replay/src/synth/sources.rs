//! The non-speech sources: emotion (level, per-sentence intensity, slow drift per direction;
//! the points themselves live in [`space`](super::space)), blinks and rigid
//! head motion. Emotion and blinks are independent of the sentence's content; brow emphasis
//! lives with the sentence in [`speech`](super::speech).

use std::f64::consts::PI;

use rand::Rng;
use serde::{Deserialize, Serialize};

use super::seeds::{name_key, sub_rng, Stream};
use super::space::emotion_points;

/// Relative spread of the emotion intensity between sentences (±).
pub const INTENSITY_SPREAD: f64 = 0.15;
/// Peak amplitude of the slow within-take emotion drift (source units), on each direction.
pub const DRIFT_AMPLITUDE: f64 = 0.1;

/// The base level of each emotion on a single emotion direction, in list order: neutral 0,
/// happy +1, frustrated -1; other names get 0.5, -0.5, 1.5, -1.5, 2, -2, ... in the order they
/// appear (skipping levels a known name already holds), then keep stepping by 0.5 outwards.
/// The one-direction case of [`emotion_points`].
pub fn emotion_levels(names: &[String]) -> Vec<f64> {
    emotion_points(names, 1, &[])
        .into_iter()
        .map(|p| p[0])
        .collect()
}

/// Intensity factor of an emotion in one sentence, in `1 ± INTENSITY_SPREAD`: the same
/// emotion is acted a little more or less strongly from sentence to sentence. It scales the
/// emotion's whole point, so every direction of a take is scaled by the same factor.
pub fn sentence_intensity(seed: u64, sentence: usize, emotion: &str) -> f64 {
    let mut rng = sub_rng(seed, Stream::Intensity, sentence as u64, name_key(emotion));
    1.0 + rng.random_range(-INTENSITY_SPREAD..INTENSITY_SPREAD)
}

/// A smooth random signal: a sum of sinusoids with random frequencies and phases.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Wobble {
    /// (amplitude, frequency Hz, phase rad) of each sinusoid.
    pub terms: Vec<(f64, f64, f64)>,
}

impl Wobble {
    /// `count` sinusoids with frequencies in `freq_hz`, whose amplitudes sum to `amplitude`.
    pub fn random(rng: &mut impl Rng, count: usize, amplitude: f64, freq_hz: (f64, f64)) -> Wobble {
        let weights: Vec<f64> = (0..count).map(|_| rng.random_range(0.5..1.0)).collect();
        let total: f64 = weights.iter().sum();
        let terms = weights
            .iter()
            .map(|w| {
                let f = rng.random_range(freq_hz.0..freq_hz.1);
                (amplitude * w / total, f, rng.random_range(0.0..2.0 * PI))
            })
            .collect();
        Wobble { terms }
    }

    /// Value at time `t` seconds.
    pub fn at(&self, t: f64) -> f64 {
        self.terms
            .iter()
            .map(|&(a, f, p)| a * (2.0 * PI * f * t + p).sin())
            .sum()
    }
}

/// The emotion drift of a take (real time) on the first emotion direction: periods of about 3
/// to 10 seconds.
pub fn emotion_drift(take_seed: u64) -> Wobble {
    let mut rng = sub_rng(take_seed, Stream::Drift, 0, 0);
    Wobble::random(&mut rng, 2, DRIFT_AMPLITUDE, (0.1, 0.33))
}

/// The emotion drift of a take on each of `dims` directions, independent of each other: the
/// first is [`emotion_drift`], the others come from their own streams, so adding directions
/// never changes the first.
pub fn emotion_drifts(take_seed: u64, dims: usize) -> Vec<Wobble> {
    (0..dims)
        .map(|d| {
            if d == 0 {
                return emotion_drift(take_seed);
            }
            let mut rng = sub_rng(take_seed, Stream::DirectionDrift, d as u64, 0);
            Wobble::random(&mut rng, 2, DRIFT_AMPLITUDE, (0.1, 0.33))
        })
        .collect()
}

/// One blink, in real time.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BlinkEvent {
    /// Start, seconds from the first frame.
    pub start_s: f64,
    /// Duration (close + open), seconds, 0.10 to 0.25.
    pub duration_s: f64,
    /// Peak value of the `blink` source (1 = fully closed).
    pub amplitude: f64,
}

/// Range of blink durations, seconds.
pub const BLINK_DURATION_S: (f64, f64) = (0.10, 0.25);
/// Range of intervals between blink starts, seconds.
pub const BLINK_INTERVAL_S: (f64, f64) = (2.0, 6.0);
/// Share of a blink spent closing (closing is faster than opening).
const BLINK_CLOSE_SHARE: f64 = 0.4;

/// Blinks of a take lasting `duration_s`: the first starts 0.2 to 4 s in (the blink process
/// runs on from before the take), then every 2 to 6 s; each ends inside the take.
pub fn blink_events(take_seed: u64, duration_s: f64) -> Vec<BlinkEvent> {
    let mut rng = sub_rng(take_seed, Stream::Blink, 0, 0);
    let mut events = Vec::new();
    let mut t = rng.random_range(0.2..4.0);
    loop {
        let d = rng.random_range(BLINK_DURATION_S.0..BLINK_DURATION_S.1);
        if t + d > duration_s {
            break;
        }
        events.push(BlinkEvent {
            start_s: t,
            duration_s: d,
            amplitude: rng.random_range(0.85..1.0),
        });
        t += rng.random_range(BLINK_INTERVAL_S.0..BLINK_INTERVAL_S.1);
    }
    events
}

/// The `blink` source at real time `t`: a fast raised-cosine close, a slower open.
pub fn blink_at(events: &[BlinkEvent], t: f64) -> f64 {
    events
        .iter()
        .map(|e| {
            let p = (t - e.start_s) / e.duration_s;
            if !(0.0..=1.0).contains(&p) {
                0.0
            } else if p < BLINK_CLOSE_SHARE {
                e.amplitude * 0.5 * (1.0 - (PI * p / BLINK_CLOSE_SHARE).cos())
            } else {
                let q = (p - BLINK_CLOSE_SHARE) / (1.0 - BLINK_CLOSE_SHARE);
                e.amplitude * 0.5 * (1.0 + (PI * q).cos())
            }
        })
        .sum()
}

/// Peak rotation of the head about each axis, radians (about 2.3 degrees).
pub const HEAD_ROTATION_RAD: f64 = 0.04;
/// Peak translation of the head along each axis, mm.
pub const HEAD_TRANSLATION_MM: f64 = 3.0;

/// Rigid head motion of a take: pitch, yaw, roll (rad) and x, y, z translation (mm).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeadMotion {
    /// One smooth signal per pose parameter.
    pub axes: Vec<Wobble>,
}

impl HeadMotion {
    /// The head motion of a take (0.1 to 0.6 Hz sway).
    pub fn for_take(take_seed: u64) -> HeadMotion {
        let mut rng = sub_rng(take_seed, Stream::Head, 0, 0);
        let axes = (0..6)
            .map(|i| {
                let amp = if i < 3 {
                    HEAD_ROTATION_RAD
                } else {
                    HEAD_TRANSLATION_MM
                };
                Wobble::random(&mut rng, 3, amp, (0.1, 0.6))
            })
            .collect();
        HeadMotion { axes }
    }

    /// Pose at real time `t`: [pitch, yaw, roll, tx, ty, tz].
    pub fn at(&self, t: f64) -> [f64; 6] {
        std::array::from_fn(|i| self.axes[i].at(t))
    }
}

#[cfg(test)]
mod tests;
