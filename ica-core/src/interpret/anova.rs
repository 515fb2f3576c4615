//! The three least-squares fits of the emotion test ([`super::emotion_effects`]) without
//! building their design matrices: take levels on sentences alone, on emotions alone, and on
//! both (additive). Dense dummy designs are `N x (S + E)`, which grows as the square of the
//! session (a 4-hour session of 4,500 takes over 1,500 sentences needs about 55 MB per copy
//! and 20 GFLOP per fit); here each fit costs O(N) per component after one `(E − 1)²` system.
//!
//! Sentences alone and emotions alone are group means. The additive fit follows from the
//! Frisch–Waugh–Lovell theorem: centre the levels and the emotion dummies within each sentence,
//! then regress one on the other; `RSS₁ = RSS₀ − bᵀβ` with `b = D̃ᵀỹ` and `D̃ᵀD̃ β = b`.

use nalgebra::{Cholesky, DMatrix, DVector, Dyn};

/// Residual sums of squares of one component's levels under the three fits.
#[derive(Debug, Clone, Copy)]
pub(super) struct Fits {
    /// Sentences and emotions (additive).
    pub full: f64,
    /// Sentences alone.
    pub sentences: f64,
    /// Emotions alone.
    pub emotions: f64,
}

/// The block structure of the takes: each take's sentence and emotion, and the counts.
#[derive(Debug)]
pub(super) struct Blocks {
    sentence: Vec<usize>,
    emotion: Vec<usize>,
    per_sentence: Vec<f64>,
    per_emotion: Vec<f64>,
    /// `D̃ᵀD̃` of the emotion dummies (emotions 1..E) centred within sentences, factored;
    /// `None` when the emotions are confounded with the sentences.
    within: Option<Cholesky<f64, Dyn>>,
}

impl Blocks {
    /// Takes with sentence `sentence[r] < s` and emotion `emotion[r] < e` (`e ≥ 2`).
    pub(super) fn new(sentence: Vec<usize>, emotion: Vec<usize>, s: usize, e: usize) -> Self {
        let mut per_sentence = vec![0.0; s];
        let mut per_emotion = vec![0.0; e];
        let mut cell = vec![0.0; s * e];
        for (&si, &ei) in sentence.iter().zip(&emotion) {
            per_sentence[si] += 1.0;
            per_emotion[ei] += 1.0;
            cell[si * e + ei] += 1.0;
        }
        let d = e - 1;
        let mut gram = DMatrix::<f64>::zeros(d, d);
        for (si, n) in per_sentence.iter().enumerate() {
            let row = &cell[si * e + 1..(si + 1) * e];
            for a in 0..d {
                gram[(a, a)] += row[a];
                for b in 0..d {
                    gram[(a, b)] -= row[a] * row[b] / n;
                }
            }
        }
        Self {
            sentence,
            emotion,
            per_sentence,
            per_emotion,
            within: gram.cholesky(),
        }
    }

    /// The additive fit's effects of levels `y`: one per emotion (the first emotion's is 0)
    /// and one per sentence, so that take `r` is fitted by
    /// `sentence[sentence(r)] + emotion[emotion(r)]`; `None` when it is singular.
    pub(super) fn effects(&self, y: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
        let within = self.within.as_ref()?;
        let s_mean = group_means(y, &self.sentence, &self.per_sentence);
        let mut b = DVector::<f64>::zeros(self.per_emotion.len() - 1);
        for (r, &v) in y.iter().enumerate() {
            if self.emotion[r] > 0 {
                b[self.emotion[r] - 1] += v - s_mean[self.sentence[r]];
            }
        }
        let beta = within.solve(&b);
        let emotion: Vec<f64> = std::iter::once(0.0).chain(beta.iter().copied()).collect();
        let shifted: Vec<f64> = y
            .iter()
            .enumerate()
            .map(|(r, v)| v - emotion[self.emotion[r]])
            .collect();
        Some((
            emotion,
            group_means(&shifted, &self.sentence, &self.per_sentence),
        ))
    }

    /// The three fits of levels `y` (one per take); `None` when the additive fit is singular.
    pub(super) fn fit(&self, y: &[f64]) -> Option<Fits> {
        let within = self.within.as_ref()?;
        let s_mean = group_means(y, &self.sentence, &self.per_sentence);
        let e_mean = group_means(y, &self.emotion, &self.per_emotion);
        let (mut sentences, mut emotions) = (0.0, 0.0);
        let mut b = DVector::<f64>::zeros(self.per_emotion.len() - 1);
        for (r, &v) in y.iter().enumerate() {
            let centred = v - s_mean[self.sentence[r]];
            sentences += centred * centred;
            emotions += (v - e_mean[self.emotion[r]]).powi(2);
            if self.emotion[r] > 0 {
                b[self.emotion[r] - 1] += centred;
            }
        }
        let beta = within.solve(&b);
        Some(Fits {
            full: (sentences - b.dot(&beta)).max(0.0),
            sentences,
            emotions,
        })
    }
}

fn group_means(y: &[f64], group: &[usize], count: &[f64]) -> Vec<f64> {
    let mut sum = vec![0.0; count.len()];
    for (&v, &g) in y.iter().zip(group) {
        sum[g] += v;
    }
    sum.iter().zip(count).map(|(s, n)| s / n).collect()
}
