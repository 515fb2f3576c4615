//! The emotion space an analysis finds: the components whose take levels differ between
//! emotions (the blocked F test of [`ica_core::interpret::emotion_effects`]), each emotion's
//! point in them (mean and spread over its takes), and the emotions that cannot be told apart;
//! then the space the edits use, fitted over every component so that it does not depend on how
//! ICA split the emotion ([`ica_core::interpret::emotion_basis`], issue 34), and whether the
//! components alone would have been a sound set of axes ([`Conditioning`]).

use std::collections::BTreeMap;

use ica_core::interpret::{
    emotion_basis, emotion_effects, emotion_subspace, BasisTake, EmotionBasis, EmotionEffect,
    TakeMeans,
};
use ica_core::model::{Conditioning, EmotionPoint};
use serde::Serialize;

/// Two emotions whose points are closer than this many times their spread cannot be told
/// apart: their takes overlap.
pub const DISTINCT_SPREADS: f64 = 2.0;
/// An emotion component is labelled [`ica_core::model::Role::Emotion`] when the emotions explain
/// at least this share of its take levels; below, it keeps the role its regions give (a speech
/// component whose level shifts a little with emotion is still speech) while the edits still
/// move it.
pub const EMOTION_ROLE_SHARE: f64 = 0.5;

/// An F statistic as the reports print it: one decimal, or three significant digits in
/// scientific notation from 10^5 up. An injected or noiseless effect reaches F in the hundreds
/// of millions, whose last digits say nothing and read as a mistake.
pub fn f_text(f: f64) -> String {
    if f.abs() >= 1e5 {
        format!("{f:.2e}")
    } else {
        format!("{f:.1}")
    }
}

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
    /// The space the edits use, fitted over every component (absent when the session cannot
    /// tell).
    pub basis: Option<BasisReport>,
    /// Whether the emotion components alone would make a sound space, and what was done.
    pub conditioning: Option<Conditioning>,
}

/// The fitted space, as the report shows it.
#[derive(Debug, Clone, Serialize)]
pub struct BasisReport {
    /// Its axes as weights on the components.
    pub axes: Vec<Vec<f64>>,
    /// The components a unit move along each axis changes.
    pub moves: Vec<Vec<f64>>,
    /// Each emotion's point over the axes.
    pub points: BTreeMap<String, EmotionPoint>,
    /// Each axis's persistence.
    pub persistence: Vec<f64>,
    /// The tests of the candidate directions, strongest first.
    pub tests: Vec<ica_core::interpret::AxisTest>,
    /// Whether the takes' offsets came from DTW-aligned pairs.
    pub aligned: bool,
}

impl From<EmotionBasis> for BasisReport {
    fn from(b: EmotionBasis) -> BasisReport {
        BasisReport {
            axes: b.project,
            moves: b.moves,
            points: b.points,
            persistence: b.persistence,
            tests: b.tests,
            aligned: b.aligned,
        }
    }
}

/// Condition number of the emotions' points on their components above which the components
/// are an ill-conditioned set of axes.
pub const CONDITION_LIMIT: f64 = 10.0;
/// Best-match correlation across restarts below which a component is unstable (as `train`
/// warns).
pub const STABLE_MATCH: f64 = 0.9;
/// Correlation of two emotion components' take levels at and above which they move together.
pub const COLLINEAR_R: f64 = 0.9;

/// One take for the space: sentence, emotion, and the mean of each component.
#[derive(Debug, Clone)]
pub struct TakeLevel {
    /// Sentence id.
    pub sentence: String,
    /// Emotion name.
    pub emotion: String,
    /// Mean of each component over the take.
    pub means: Vec<f64>,
    /// Its offset from its sentence's first take over DTW-aligned frames (zeros for that
    /// take; `None` without pairs).
    pub aligned: Option<Vec<f64>>,
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
    let basis_takes: Vec<BasisTake<'_>> = takes
        .iter()
        .map(|t| BasisTake {
            sentence: &t.sentence,
            emotion: &t.emotion,
            means: &t.means,
            aligned: t.aligned.as_deref(),
        })
        .collect();
    let basis = emotion_basis(&basis_takes, m).map(BasisReport::from);
    EmotionSpace {
        axes,
        persistence,
        effects,
        components,
        main,
        points,
        indistinct,
        basis,
        conditioning: None,
    }
}

/// Whether the emotion components of `space` would be a sound set of axes on their own, from
/// their points, the takes' levels and each component's `stability` across restarts (empty:
/// not measured), and what the edits do instead.
pub fn conditioning(space: &EmotionSpace, takes: &[TakeLevel], stability: &[f64]) -> Conditioning {
    // The components that would be the axes: those the emotions explain (components that only
    // shift a little with emotion keep their region role and are not axes).
    let ks = &space.axes;
    let dims = space.basis.as_ref().map_or(0, |b| b.axes.len());
    let at: Vec<usize> = ks
        .iter()
        .filter_map(|k| space.components.iter().position(|c| c == k))
        .collect();
    let levels: Vec<Vec<f64>> = space
        .points
        .values()
        .map(|p| at.iter().map(|&i| p.level[i]).collect())
        .collect();
    let condition = condition_number(&levels, ks.len());
    let unstable: Vec<(usize, f64)> = ks
        .iter()
        .filter_map(|&k| stability.get(k).map(|&r| (k, r)))
        .filter(|&(_, r)| r < STABLE_MATCH)
        .collect();
    let mut collinear = Vec::new();
    for (i, &a) in ks.iter().enumerate() {
        for &b in &ks[i + 1..] {
            let r = correlation(takes.iter().map(|t| (t.means[a], t.means[b])));
            if r.abs() >= COLLINEAR_R {
                collinear.push((a, b, r));
            }
        }
    }
    let ill_conditioned = ks.len() > dims
        || condition > CONDITION_LIMIT
        || !unstable.is_empty()
        || !collinear.is_empty();
    let note = conditioning_note(ks, dims, &unstable, &collinear, condition, takes);
    Conditioning {
        components: ks.clone(),
        dims,
        condition,
        unstable,
        collinear,
        ill_conditioned,
        note,
    }
}

fn names(ks: &[usize]) -> String {
    ks.iter()
        .map(|k| format!("c{k}"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn conditioning_note(
    ks: &[usize],
    dims: usize,
    unstable: &[(usize, f64)],
    collinear: &[(usize, usize, f64)],
    condition: f64,
    takes: &[TakeLevel],
) -> String {
    let m = takes.first().map_or(0, |t| t.means.len());
    let mut why = Vec::new();
    if ks.len() > dims {
        why.push(format!(
            "{} components for {dims} dimension{}",
            ks.len(),
            if dims == 1 { "" } else { "s" }
        ));
    }
    for (a, b, r) in collinear {
        why.push(format!("c{a} and c{b} move together (r = {r:.2})"));
    }
    if !unstable.is_empty() {
        let list: Vec<String> = unstable
            .iter()
            .map(|(k, r)| format!("c{k} {r:.2}"))
            .collect();
        why.push(format!(
            "not found again by other restarts: {}",
            list.join(", ")
        ));
    }
    if condition > CONDITION_LIMIT && ks.len() <= dims {
        why.push(format!("condition number {condition:.0}"));
    }
    let done = format!(
        "the edits move along {dims} axes fitted over all {m} components, which do not depend on how ICA split the emotion"
    );
    if ks.is_empty() {
        format!("no single component carries emotion; {done}")
    } else if why.is_empty() {
        format!(
            "the emotion components {} are sound axes; {done}",
            names(ks)
        )
    } else {
        format!(
            "the emotion components {} are ill-conditioned as axes ({}); {done}",
            names(ks),
            why.join("; ")
        )
    }
}

/// Largest over smallest singular value of the centred points (emotions x `k`), over the
/// `min(k, emotions - 1)` dimensions the points can span; 1 with fewer than two points.
fn condition_number(levels: &[Vec<f64>], k: usize) -> f64 {
    let e = levels.len();
    if e < 2 || k == 0 {
        return 1.0;
    }
    let mean: Vec<f64> = (0..k)
        .map(|j| levels.iter().map(|l| l[j]).sum::<f64>() / e as f64)
        .collect();
    let centred = nalgebra::DMatrix::from_fn(e, k, |i, j| levels[i][j] - mean[j]);
    let mut sv: Vec<f64> = centred.singular_values().iter().copied().collect();
    sv.sort_by(|a, b| b.total_cmp(a));
    let rank = k.min(e - 1);
    let smallest = sv[rank - 1];
    if smallest <= sv[0] * 1e-12 {
        return 1e12;
    }
    sv[0] / smallest
}

fn correlation(pairs: impl Iterator<Item = (f64, f64)> + Clone) -> f64 {
    let n = pairs.clone().count().max(1) as f64;
    let (ma, mb) = pairs
        .clone()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in pairs {
        sab += (x - ma) * (y - mb);
        saa += (x - ma).powi(2);
        sbb += (y - mb).powi(2);
    }
    sab / (saa * sbb).sqrt().max(1e-300)
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

#[cfg(test)]
mod tests {
    #[test]
    fn large_f_statistics_print_in_scientific_notation() {
        assert_eq!(super::f_text(12.34), "12.3");
        assert_eq!(super::f_text(99_999.94), "99999.9");
        assert_eq!(super::f_text(154_817_631.7), "1.55e8");
    }
}
