//! Which components carry emotion: a test across paired takes.
//!
//! Each take's mean of a component is one observation `y`. Takes of the same sentence in
//! different emotions form a block (a randomised block design): `y = μ + α_sentence +
//! β_emotion + ε`. The emotion effect is tested with the F statistic of the block model against
//! the model without `β` (Fisher's two-way analysis of variance without interaction, by least
//! squares so unbalanced sessions work):
//!
//! `F = ((RSS₀ − RSS₁) / (E − 1)) / (RSS₁ / (N − S − E + 1))`
//!
//! with `N` takes, `S` sentences and `E` emotions. Sentences spoken in one emotion only carry no
//! paired information and are left out. With two emotions this is the paired t-test on the
//! differences of take means, squared. Speech, blinks and noise average out over a take or
//! differ by sentence (the blocks absorb that); emotion shifts a component's level for a whole
//! take. The fits use the block structure rather than dummy design matrices ([`super::anova`]),
//! so their cost grows with the takes, not with takes times sentences. A component belongs to
//! the emotion subspace when its p-value is below
//! [`EMOTION_ALPHA`] divided by the number of components tested (Bonferroni).

use std::collections::BTreeMap;

use nalgebra::DVector;

use super::anova::Blocks;
use serde::{Deserialize, Serialize};

/// Family-wise error rate of the emotion test over all components.
pub const EMOTION_ALPHA: f64 = 1e-3;

/// One take's component means, with its sentence and emotion.
#[derive(Debug, Clone, Copy)]
pub struct TakeMeans<'a> {
    /// Sentence id.
    pub sentence: &'a str,
    /// Emotion name.
    pub emotion: &'a str,
    /// Mean of each component over the take.
    pub means: &'a [f64],
}

/// The emotion effect on one component.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EmotionEffect {
    /// F statistic (0 when it cannot be computed).
    pub f: f64,
    /// Degrees of freedom of the effect, `E − 1`.
    pub df_effect: usize,
    /// Degrees of freedom of the error, `N − S − E + 1`.
    pub df_error: usize,
    /// p-value of the F test (1 when it cannot be computed).
    pub p: f64,
    /// Share of a take's deviation from its emotion's mean that belongs to its sentence and so
    /// persists when the same sentence is spoken in another emotion: `σ²_s / (σ²_s + σ²_ε)`,
    /// from the sentence mean square adjusted for emotion (`E[MS_s] = σ²_ε + n̄ σ²_s`, `n̄` the
    /// takes per sentence). 0 for a pure emotion level, near 1 for a component whose level is
    /// the sentence's content.
    #[serde(default)]
    pub sentence_share: f64,
    /// Share of the component's take-level variance the emotions explain (η², after the
    /// sentences): near 1 for a component that is an emotion axis, small for one that is
    /// mostly speech with a slight emotion shift.
    #[serde(default)]
    pub emotion_share: f64,
}

/// The emotion effect on each of the `m` components. Needs at least one sentence in two
/// emotions and more takes than parameters; otherwise every effect is `F = 0, p = 1`.
pub fn emotion_effects(takes: &[TakeMeans<'_>], m: usize) -> Vec<EmotionEffect> {
    let mut emotions_of: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
    for t in takes {
        let e = emotions_of.entry(t.sentence).or_default();
        if !e.contains(&t.emotion) {
            e.push(t.emotion);
        }
    }
    let used: Vec<&TakeMeans<'_>> = takes
        .iter()
        .filter(|t| emotions_of[t.sentence].len() >= 2)
        .collect();
    let sentences: Vec<&str> = dedup(used.iter().map(|t| t.sentence));
    let emotions: Vec<&str> = dedup(used.iter().map(|t| t.emotion));
    let (n, s, e) = (used.len(), sentences.len(), emotions.len());
    let none = EmotionEffect {
        f: 0.0,
        df_effect: e.saturating_sub(1),
        df_error: 0,
        p: 1.0,
        sentence_share: 0.0,
        emotion_share: 0.0,
    };
    if e < 2 || n < s + e {
        return vec![none; m];
    }
    let df_error = n - s - e + 1;
    let (s_at, e_at) = (index_of(&sentences), index_of(&emotions));
    let blocks = Blocks::new(
        used.iter().map(|t| s_at[t.sentence]).collect(),
        used.iter().map(|t| e_at[t.emotion]).collect(),
        s,
        e,
    );
    let per_sentence = n as f64 / s as f64;
    (0..m)
        .map(|k| {
            let y = DVector::from_fn(n, |r, _| used[r].means[k]);
            let Some(fits) = blocks.fit(y.as_slice()) else {
                return none;
            };
            let (rss1, rss0, rss_e) = (fits.full, fits.sentences, fits.emotions);
            let effect = (rss0 - rss1).max(0.0) / (e - 1) as f64;
            let error = rss1 / df_error as f64;
            let f = if error > 0.0 {
                effect / error
            } else {
                f64::INFINITY
            };
            let ms_sentence = if s > 1 {
                (rss_e - rss1).max(0.0) / (s - 1) as f64
            } else {
                0.0
            };
            let var_sentence = ((ms_sentence - error) / per_sentence).max(0.0);
            let total = var_sentence + error;
            let mean = y.mean();
            let ss_total: f64 = y.iter().map(|v| (v - mean).powi(2)).sum();
            EmotionEffect {
                emotion_share: if ss_total > 0.0 {
                    ((rss0 - rss1) / ss_total).clamp(0.0, 1.0)
                } else {
                    0.0
                },
                f,
                df_effect: e - 1,
                df_error,
                p: f_upper_tail(f, (e - 1) as f64, df_error as f64),
                sentence_share: if total > 0.0 {
                    var_sentence / total
                } else {
                    0.0
                },
            }
        })
        .collect()
}

/// The components whose emotion effect is significant at [`EMOTION_ALPHA`] over all of them.
pub fn emotion_subspace(effects: &[EmotionEffect]) -> Vec<usize> {
    let threshold = EMOTION_ALPHA / effects.len().max(1) as f64;
    (0..effects.len())
        .filter(|&k| effects[k].p < threshold)
        .collect()
}

fn index_of<'a>(names: &[&'a str]) -> BTreeMap<&'a str, usize> {
    names.iter().enumerate().map(|(i, n)| (*n, i)).collect()
}

fn dedup<'a>(items: impl Iterator<Item = &'a str>) -> Vec<&'a str> {
    let mut out: Vec<&str> = Vec::new();
    for i in items {
        if !out.contains(&i) {
            out.push(i);
        }
    }
    out
}

/// `P(F > f)` for an F distribution with `d1`, `d2` degrees of freedom:
/// `I_{d2/(d2 + d1 f)}(d2/2, d1/2)`.
pub fn f_upper_tail(f: f64, d1: f64, d2: f64) -> f64 {
    if f.is_nan() {
        return 1.0;
    }
    if f.is_infinite() {
        return 0.0;
    }
    if f <= 0.0 {
        return 1.0;
    }
    incomplete_beta(d2 / (d2 + d1 * f), d2 / 2.0, d1 / 2.0)
}

/// The regularised incomplete beta function `I_x(a, b)` (continued fraction, Lentz's method).
fn incomplete_beta(x: f64, a: f64, b: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let ln_front = ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln();
    // The continued fraction converges fast for x < (a + 1) / (a + b + 2); use the symmetry
    // I_x(a, b) = 1 − I_{1−x}(b, a) otherwise.
    if x < (a + 1.0) / (a + b + 2.0) {
        ln_front.exp() * beta_fraction(x, a, b) / a
    } else {
        1.0 - ln_front.exp() * beta_fraction(1.0 - x, b, a) / b
    }
}

fn beta_fraction(x: f64, a: f64, b: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 - qab * x / qap;
    if d.abs() < TINY {
        d = TINY;
    }
    d = 1.0 / d;
    let mut h = d;
    for m in 1..300 {
        let m = f64::from(m);
        let m2 = 2.0 * m;
        let aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 + aa * d;
        d = if d.abs() < TINY { TINY } else { d };
        c = 1.0 + aa / c;
        c = if c.abs() < TINY { TINY } else { c };
        d = 1.0 / d;
        h *= d * c;
        let aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 + aa * d;
        d = if d.abs() < TINY { TINY } else { d };
        c = 1.0 + aa / c;
        c = if c.abs() < TINY { TINY } else { c };
        d = 1.0 / d;
        let delta = d * c;
        h *= delta;
        if (delta - 1.0).abs() < 1e-14 {
            break;
        }
    }
    h
}

/// `ln Γ(x)` for `x > 0` (Lanczos, g = 7, 9 terms; ~1e-15 relative).
fn ln_gamma(x: f64) -> f64 {
    const G: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Γ(x) Γ(1 − x) = π / sin(πx).
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let t = x + 7.5;
    let series = G[1..]
        .iter()
        .enumerate()
        .fold(G[0], |acc, (i, g)| acc + g / (x + i as f64 + 1.0));
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + series.ln()
}

#[cfg(test)]
mod tests;
