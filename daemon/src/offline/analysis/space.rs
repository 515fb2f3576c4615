//! The emotion space an analysis finds: the components whose take levels differ between
//! emotions (the blocked F test of [`ica_core::interpret::emotion_effects`]), each emotion's
//! point in them (mean and spread over its takes), and the emotions that cannot be told apart.

use std::collections::BTreeMap;

use ica_core::interpret::{emotion_effects, emotion_subspace, EmotionEffect, TakeMeans};
use ica_core::model::EmotionPoint;
use serde::Serialize;

/// Two emotions whose points are closer than this many times their spread cannot be told
/// apart: their takes overlap.
pub const DISTINCT_SPREADS: f64 = 2.0;
/// An emotion component is labelled [`ica_core::model::Role::Emotion`] when the emotions explain
/// at least this share of its take levels; below, it keeps the role its regions give (a speech
/// component whose level shifts a little with emotion is still speech) while the edits still
/// move it.
pub const EMOTION_ROLE_SHARE: f64 = 0.5;

/// Two emotions that cannot be told apart.
#[derive(Debug, Clone, Serialize)]
pub struct Indistinct {
    /// One emotion.
    pub a: String,
    /// The other.
    pub b: String,
    /// Distance between their points (component units).
    pub distance: f64,
    /// Their pooled spread: the RMS of the two points' spreads (component units).
    pub spread: f64,
}

/// The emotion space of a session. See the module docs.
#[derive(Debug, Clone, Serialize)]
pub struct EmotionSpace {
    /// The emotion effect on every component.
    pub effects: Vec<EmotionEffect>,
    /// The emotion components, ascending: every component whose levels differ between
    /// emotions; the edits move all of them.
    pub components: Vec<usize>,
    /// The components among them that are emotion axes ([`EMOTION_ROLE_SHARE`]).
    pub axes: Vec<usize>,
    /// The component with the strongest effect (largest F).
    pub main: Option<usize>,
    /// Each emotion's point over `components`.
    pub points: BTreeMap<String, EmotionPoint>,
    /// Each emotion component's sentence share (see
    /// [`ica_core::interpret::EmotionEffect::sentence_share`]).
    pub persistence: Vec<f64>,
    /// Pairs of emotions closer than [`DISTINCT_SPREADS`] spreads.
    pub indistinct: Vec<Indistinct>,
}

/// One take for the space: sentence, emotion, and the mean of each component.
#[derive(Debug, Clone)]
pub struct TakeLevel {
    /// Sentence id.
    pub sentence: String,
    /// Emotion name.
    pub emotion: String,
    /// Mean of each component over the take.
    pub means: Vec<f64>,
}

/// Finds the emotion space of `takes` (each with its component means) for `m` components.
pub fn emotion_space(takes: &[TakeLevel], m: usize) -> EmotionSpace {
    let input: Vec<TakeMeans<'_>> = takes
        .iter()
        .map(|t| TakeMeans {
            sentence: &t.sentence,
            emotion: &t.emotion,
            means: &t.means,
        })
        .collect();
    let effects = emotion_effects(&input, m);
    let components = emotion_subspace(&effects);
    let main = components
        .iter()
        .copied()
        .max_by(|&a, &b| effects[a].f.total_cmp(&effects[b].f));
    let points = if components.is_empty() {
        BTreeMap::new()
    } else {
        points(takes, &components)
    };
    let indistinct = indistinct(&points);
    let persistence = components
        .iter()
        .map(|&k| effects[k].sentence_share)
        .collect();
    let axes = components
        .iter()
        .copied()
        .filter(|&k| effects[k].emotion_share >= EMOTION_ROLE_SHARE)
        .collect();
    EmotionSpace {
        axes,
        persistence,
        effects,
        components,
        main,
        points,
        indistinct,
    }
}

/// Mean and sample standard deviation of each emotion's takes over `components`.
fn points(takes: &[TakeLevel], components: &[usize]) -> BTreeMap<String, EmotionPoint> {
    let mut by_emotion: BTreeMap<&str, Vec<&TakeLevel>> = BTreeMap::new();
    for t in takes {
        by_emotion.entry(&t.emotion).or_default().push(t);
    }
    by_emotion
        .into_iter()
        .map(|(name, ts)| {
            let n = ts.len() as f64;
            let level: Vec<f64> = components
                .iter()
                .map(|&k| ts.iter().map(|t| t.means[k]).sum::<f64>() / n)
                .collect();
            let spread = components
                .iter()
                .zip(&level)
                .map(|(&k, mean)| {
                    if ts.len() < 2 {
                        return 0.0;
                    }
                    let ss: f64 = ts.iter().map(|t| (t.means[k] - mean).powi(2)).sum();
                    (ss / (n - 1.0)).sqrt()
                })
                .collect();
            (
                name.to_string(),
                EmotionPoint {
                    level,
                    spread,
                    takes: ts.len(),
                },
            )
        })
        .collect()
}

fn norm(v: impl Iterator<Item = f64>) -> f64 {
    v.map(|x| x * x).sum::<f64>().sqrt()
}

fn indistinct(points: &BTreeMap<String, EmotionPoint>) -> Vec<Indistinct> {
    let named: Vec<(&String, &EmotionPoint)> = points.iter().collect();
    let mut out = Vec::new();
    for (i, (a, pa)) in named.iter().enumerate() {
        for (b, pb) in &named[i + 1..] {
            let distance = norm(pa.level.iter().zip(&pb.level).map(|(x, y)| x - y));
            let spread = ((norm(pa.spread.iter().copied()).powi(2)
                + norm(pb.spread.iter().copied()).powi(2))
                / 2.0)
                .sqrt();
            if distance < DISTINCT_SPREADS * spread {
                out.push(Indistinct {
                    a: (*a).clone(),
                    b: (*b).clone(),
                    distance,
                    spread,
                });
            }
        }
    }
    out
}
