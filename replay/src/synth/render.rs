//! Rendering one take: sources from the sentence, emotion, blinks and head motion; mixed
//! linearly onto the rest face; rigid head motion; sensor noise.

use rand_distr::{Distribution, Normal};

use super::mixing::HEAD_PIVOT;
use super::seeds::{sub_rng, Stream};
use super::sources::{blink_at, blink_events, emotion_drifts, HeadMotion};
use super::truth::TakeTruth;
use super::warp::Warp;
use super::{Synth, SynthError};
use crate::Take;

/// Standard deviation of the sensor noise per coordinate, mm.
pub const NOISE_STD_MM: f64 = 0.2;

/// Everything that decides one take. Build it with [`Synth::take_spec`]; to render sentence S
/// in emotion B with the timing of S's take in emotion A, use
/// `synth.take_spec(s, "B")?.with_timing_of(&spec_a)`; to render S's take in A at any level
/// vector (a blend, a shifted point) with A's timing, use `spec_a.with_levels(levels)`.
#[derive(Debug, Clone, PartialEq)]
pub struct TakeSpec {
    /// 0-based sentence index.
    pub sentence: usize,
    /// Emotion name (labels the take; the level below is what is rendered).
    pub emotion: String,
    /// Level rendered on each emotion direction: the emotion's base point x per-sentence
    /// intensity (one level per direction; the emotion sources are these plus a slow drift).
    pub emotion_levels: Vec<f64>,
    /// Canonical time of each frame; decides the frame count.
    pub warp: Warp,
    /// Seed of the take's real-time randomness: emotion drift, blinks, head motion, noise.
    pub seed: u64,
    /// Whether to add sensor noise ([`NOISE_STD_MM`]).
    pub noise: bool,
}

impl TakeSpec {
    /// This spec with the timing and real-time randomness (warp, drift, blinks, head motion,
    /// noise) of `other`: the same performance, acted in this spec's emotion.
    pub fn with_timing_of(mut self, other: &TakeSpec) -> TakeSpec {
        self.warp = other.warp.clone();
        self.seed = other.seed;
        self
    }

    /// This spec rendered at `levels` (one per emotion direction) instead of its emotion's:
    /// same timing, drift, blinks, head motion and noise, so two renders differ only by the
    /// emotion columns of the mixing matrix times the level change. The take keeps its
    /// emotion name; set [`TakeSpec::emotion`] to relabel it.
    pub fn with_levels(mut self, levels: Vec<f64>) -> TakeSpec {
        self.emotion_levels = levels;
        self
    }
}

/// A rendered take and its truth.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderedTake {
    /// The take (no missing samples).
    pub take: Take,
    /// Its ground truth.
    pub truth: TakeTruth,
}

/// Renders a take of `synth`.
///
/// # Errors
/// [`SynthError::SentenceOutOfRange`] for a bad sentence index, [`SynthError::WarpMismatch`]
/// when the warp does not span the sentence's canonical duration, [`SynthError::LevelDims`] or
/// [`SynthError::NonFiniteLevel`] for a level vector that is not one finite level per emotion
/// direction.
pub(crate) fn render(synth: &Synth, spec: &TakeSpec) -> Result<RenderedTake, SynthError> {
    let sentence = synth
        .sentences()
        .get(spec.sentence)
        .ok_or(SynthError::SentenceOutOfRange {
            sentence: spec.sentence,
            count: synth.sentences().len(),
        })?;
    check_levels(synth, &spec.emotion_levels)?;
    check_warp(spec, sentence)?;
    let rate = synth.params().rate_hz;
    let n = spec.warp.n_frames();
    let cols = synth.source_layout();
    let drifts = emotion_drifts(spec.seed, cols.emotion_dims());
    let blinks = blink_events(spec.seed, (n - 1) as f64 / rate);
    let head = synth
        .params()
        .head_motion
        .then(|| HeadMotion::for_take(spec.seed));
    let sources: Vec<Vec<f64>> = (0..n)
        .map(|f| {
            let (t, tau) = (f as f64 / rate, spec.warp.canonical_s[f]);
            let mut s = vec![0.0; cols.count()];
            s[..cols.speech_count()].copy_from_slice(&sentence.speech_at(tau));
            for (d, (level, drift)) in spec.emotion_levels.iter().zip(&drifts).enumerate() {
                s[cols.emotion(d)] = level + drift.at(t);
            }
            s[cols.brow_raise()] = sentence.brow_at(tau);
            s[cols.blink()] = blink_at(&blinks, t);
            if let Some(h) = &head {
                s[cols.head()..].copy_from_slice(&h.at(t));
            }
            s
        })
        .collect();
    let take = mix(synth, &sources, spec)?;
    let truth = TakeTruth {
        name: synth.take_name(spec.sentence, &spec.emotion),
        sentence: sentence.id.clone(),
        sentence_index: spec.sentence,
        emotion: spec.emotion.clone(),
        emotion_level: spec.emotion_levels[0],
        emotion_levels: spec.emotion_levels.clone(),
        seed: spec.seed,
        rate_hz: rate,
        warp: spec.warp.canonical_s.clone(),
        sources,
        blinks,
        brow_events: sentence.brow_events.clone(),
        segments: sentence.segments.clone(),
    };
    Ok(RenderedTake { take, truth })
}

/// The warp spans the sentence's canonical duration, over two frames at least.
fn check_warp(spec: &TakeSpec, sentence: &super::speech::Sentence) -> Result<(), SynthError> {
    let end = spec.warp.canonical_duration_s();
    let ok = spec.warp.n_frames() >= 2 && (end - sentence.duration_s).abs() < 1e-6;
    if !ok {
        return Err(SynthError::WarpMismatch {
            sentence: sentence.id.clone(),
            warp_s: end,
            sentence_s: sentence.duration_s,
        });
    }
    Ok(())
}

/// One finite level per emotion direction.
fn check_levels(synth: &Synth, levels: &[f64]) -> Result<(), SynthError> {
    let expected = synth.source_layout().emotion_dims();
    if levels.len() != expected {
        return Err(SynthError::LevelDims {
            expected,
            got: levels.len(),
        });
    }
    match levels.iter().find(|v| !v.is_finite()) {
        Some(&v) => Err(SynthError::NonFiniteLevel(v)),
        None => Ok(()),
    }
}

/// Mixes sources into marker positions: rest + facial columns · sources, then the exact rigid
/// head transform, then noise.
fn mix(synth: &Synth, sources: &[Vec<f64>], spec: &TakeSpec) -> Result<Take, SynthError> {
    let rest = synth.rest();
    let m = synth.mixing();
    let channels = rest.len();
    let markers = channels / 3;
    let mut noise_rng = sub_rng(spec.seed, Stream::Noise, 0, 0);
    let normal = Normal::new(0.0, NOISE_STD_MM).expect("noise std is a positive constant");
    let mut take = Take::new(synth.face().labels(), synth.params().rate_hz, 1);
    take.positions.reserve(sources.len() * channels);
    let missing = vec![false; markers];
    let mut xyz = vec![0.0f32; channels];
    let mut face = vec![0.0f64; channels];
    let (count, head) = (synth.source_layout().count(), synth.source_layout().head());
    for s in sources {
        for (c, out) in face.iter_mut().enumerate() {
            let row = &m[c * count..c * count + head];
            *out = rest[c] + row.iter().zip(&s[..head]).map(|(a, v)| a * v).sum::<f64>();
        }
        let rot = rotation(s[head], s[head + 1], s[head + 2]);
        for k in 0..markers {
            let p: [f64; 3] = std::array::from_fn(|a| face[k * 3 + a] - HEAD_PIVOT[a]);
            for a in 0..3 {
                let moved = rot[a][0] * p[0] + rot[a][1] * p[1] + rot[a][2] * p[2];
                let mut v = moved + HEAD_PIVOT[a] + s[head + 3 + a];
                if spec.noise {
                    v += normal.sample(&mut noise_rng);
                }
                xyz[k * 3 + a] = v as f32;
            }
        }
        take.push_frame(&xyz, &missing);
    }
    take.validate()?;
    Ok(take)
}

/// Rotation matrix `Rz(roll) · Ry(yaw) · Rx(pitch)`; to first order its generator is
/// (pitch, yaw, roll) about (x, y, z), matching the head columns of the mixing matrix.
fn rotation(pitch: f64, yaw: f64, roll: f64) -> [[f64; 3]; 3] {
    let (sx, cx) = pitch.sin_cos();
    let (sy, cy) = yaw.sin_cos();
    let (sz, cz) = roll.sin_cos();
    [
        [cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx],
        [sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx],
        [-sy, cy * sx, cy * cx],
    ]
}
