//! The emotion space as a subspace of component space, whatever way ICA split it (issue 34).
//!
//! The components are white, so a rotation of them (another FastICA restart, another split of
//! the emotion between components) rotates every take's levels and leaves distances alone.
//! This fit uses only rotation-free steps, so its space does not depend on the split:
//!
//! 1. Each take's *offset* `y` (m components): with pairs aligned by DTW, its mean level
//!    relative to its sentence's first take over frames matched one to one
//!    ([`super::aligned_offset`]), so what the sentence says cancels frame by frame; without,
//!    its component means.
//! 2. The additive block model `y = α_sentence + β_emotion + ε` fitted per component, as
//!    [`super::emotion_effects`] does, gives the hypothesis SSCP matrix `H` (what the emotions
//!    add to the sentences) and the error SSCP `E`.
//! 3. Directions: the canonical directions of `H` against the error covariance (shrunk, so a
//!    small session still has one), strongest first; each is kept while its own F test passes at
//!    [`super::EMOTION_ALPHA`] over the `m` components, so the dimension comes from a test,
//!    not from how many components the emotion happened to spread over.
//!    A take's position is read with those (discriminant) directions, which weigh down what
//!    varies from take to take; a move follows the emotion effects they find (`Σ v`).
//! 4. In that space, the takes' *means* (what the edit sees of a take) give each emotion's point
//!    (`a + β_e`, the emotion on the average sentence) and how far takes sit from their
//!    emotion's point, `Σ_s + Σ_ε` (sentence and take covariances). Of that, what does not
//!    persist into another emotion is what the aligned offsets leave unexplained (their error
//!    covariance: what the take says is gone from them, its own intensity is not); without
//!    aligned pairs, `Σ_ε`. The axes are turned so that both are diagonal: per axis, the
//!    persistence `ρ = 1 − σ²_own / (σ²_s + σ²_ε)` and the spreads are independent, which is
//!    what [`crate::model::SpaceTarget`] assumes.
//!
//! The result maps components to the space's coordinates (`project`, `d x m`) and a move in
//! the space back to components (`moves`, `m x d` as `d` rows, `project · moves = I`).

use std::collections::BTreeMap;

use nalgebra::{DMatrix, DVector, SymmetricEigen};
use serde::{Deserialize, Serialize};

use super::anova::Blocks;
use super::effect::{f_upper_tail, EMOTION_ALPHA};
use crate::model::EmotionPoint;

/// Relative ridge added to a covariance before it is factored (degenerate sessions).
const RIDGE: f64 = 1e-9;

/// One take for [`emotion_basis`].
#[derive(Debug, Clone, Copy)]
pub struct BasisTake<'a> {
    /// Sentence id.
    pub sentence: &'a str,
    /// Emotion name.
    pub emotion: &'a str,
    /// Mean of each component over the take.
    pub means: &'a [f64],
    /// Its offset from its sentence's first take over DTW-aligned frames (zeros for the first
    /// take itself). `None` for any take: every take's means are used instead.
    pub aligned: Option<&'a [f64]>,
}

/// The test of one candidate direction.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AxisTest {
    /// F statistic of the emotions on the takes' offsets along the direction.
    pub f: f64,
    /// Its p-value.
    pub p: f64,
    /// Whether the direction is in the space.
    pub kept: bool,
}

/// The emotion space a session shows. See the module docs.
#[derive(Debug, Clone, PartialEq)]
pub struct EmotionBasis {
    /// Coordinates of the space from components: one row of `m` weights per axis.
    pub project: Vec<Vec<f64>>,
    /// Components moved by one unit along each axis: one row of `m` per axis.
    pub moves: Vec<Vec<f64>>,
    /// Each emotion's point, spread and take count in the space's coordinates.
    pub points: BTreeMap<String, EmotionPoint>,
    /// Each axis's persistence (sentence share), 0 to 1.
    pub persistence: Vec<f64>,
    /// Every candidate direction, strongest first, with its test.
    pub tests: Vec<AxisTest>,
    /// Whether the offsets came from aligned pairs (else from take means).
    pub aligned: bool,
    /// Error degrees of freedom of the tests.
    pub df_error: usize,
}

impl EmotionBasis {
    /// Dimensions of the space.
    pub fn dims(&self) -> usize {
        self.project.len()
    }
}

/// The emotion space of `takes` over `m` components; `None` when the session cannot tell
/// (no sentence in two emotions, or no more takes than parameters).
pub fn emotion_basis(takes: &[BasisTake<'_>], m: usize) -> Option<EmotionBasis> {
    let design = Design::new(takes)?;
    let used: Vec<&BasisTake<'_>> = design.rows.iter().map(|&r| &takes[r]).collect();
    let aligned = used.iter().all(|t| t.aligned.is_some());
    let offsets = DMatrix::from_fn(used.len(), m, |r, k| match used[r].aligned {
        Some(a) if aligned => a[k],
        _ => used[r].means[k],
    });
    let (h, e) = design.sscp(&offsets)?;
    let df = design.df_error();
    let (directions, noise) = directions(&h, &e, df);
    let (mut kept, mut tests) = (Vec::new(), Vec::new());
    for v in directions.into_iter().take(design.emotions.len() - 1) {
        let (f, p) = design.f_test(&(&offsets * &v))?;
        let pass = tests.iter().all(|t: &AxisTest| t.kept) && p < EMOTION_ALPHA / m as f64;
        if pass {
            kept.push(v);
        }
        tests.push(AxisTest { f, p, kept: pass });
    }
    let mut basis = EmotionBasis {
        project: Vec::new(),
        moves: Vec::new(),
        points: BTreeMap::new(),
        persistence: Vec::new(),
        tests,
        aligned,
        df_error: df,
    };
    if kept.is_empty() {
        return Some(basis);
    }
    // Move along the effects the kept directions find (`Σ V`: with `Vᵀ Σ V = I` they span the
    // emotion effects). Read a take's position from its means with the least noise a take's
    // means carry (what it says, how it was spoken), by generalised least squares against
    // their within-emotion covariance `C`: `G = (Lᵀ C⁻¹ L)⁻¹ Lᵀ C⁻¹`, so that `G L = I`.
    let along = &noise * DMatrix::from_columns(&kept);
    let means = DMatrix::from_fn(used.len(), m, |r, k| used[r].means[k]);
    let read = design.readout(&means, &along)?;
    let read_offsets = &offsets * read.transpose();
    let beta = design.effects(&read_offsets)?;
    let coords = &means * read.transpose();
    // What of a take's position does not persist: with aligned offsets, what is left of them
    // after the sentence and the emotion (what the take says is gone from them); otherwise
    // what is left of the means.
    let [unexplained, _, _] = design.residuals(if aligned { &read_offsets } else { &coords })?;
    let own = unexplained.transpose() * &unexplained / design.df_error() as f64;
    let (points, turn, persistence) = design.space(&coords, &beta, own)?;
    let back = turn.clone().try_inverse()?;
    let project = &turn * read;
    let moves = (along * back).transpose();
    let rows = |x: &DMatrix<f64>| {
        (0..x.nrows())
            .map(|i| x.row(i).iter().copied().collect())
            .collect()
    };
    basis.project = rows(&project);
    basis.moves = rows(&moves);
    basis.persistence = persistence;
    basis.points = design
        .emotions
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let own: Vec<usize> = (0..used.len())
                .filter(|&r| design.emotion[r] == i)
                .collect();
            let level = &turn * points.row(i).transpose();
            let spread = (0..level.len())
                .map(|j| {
                    let ss: f64 = own
                        .iter()
                        .map(|&r| ((&turn * coords.row(r).transpose())[j] - level[j]).powi(2))
                        .sum();
                    if own.len() < 2 {
                        0.0
                    } else {
                        (ss / (own.len() - 1) as f64).sqrt()
                    }
                })
                .collect();
            let point = EmotionPoint {
                level: level.iter().copied().collect(),
                spread,
                takes: own.len(),
            };
            (name.to_string(), point)
        })
        .collect();
    Some(basis)
}

/// `C + s (tr C / m) I` scaled by `1 / (1 + s)`, `s = m / df`: a covariance estimate from
/// `df` degrees of freedom, shrunk towards its mean variance so that it stays invertible and
/// commutes with a rotation of the components.
fn shrunk(cov: DMatrix<f64>, df: usize) -> DMatrix<f64> {
    let m = cov.nrows();
    let mean_var = (cov.trace() / m as f64).max(f64::MIN_POSITIVE);
    let shrink = m as f64 / (m + df.max(1)) as f64;
    cov * (1.0 - shrink) + DMatrix::<f64>::identity(m, m) * (mean_var * shrink)
}

/// Candidate directions in component space, strongest first: the canonical directions of the
/// hypothesis SSCP against the error covariance (`H v = λ Σ v`), the error covariance shrunk
/// towards its mean variance by `m / (m + df)` so that a small session (fewer error degrees
/// of freedom than components) still has one. Both steps commute with a rotation of the
/// components.
fn directions(h: &DMatrix<f64>, e: &DMatrix<f64>, df: usize) -> (Vec<DVector<f64>>, DMatrix<f64>) {
    let m = h.nrows();
    let shrunk = shrunk(e / df as f64, df);
    let mean_var = shrunk.trace() / m as f64;
    let eig = SymmetricEigen::new(shrunk.clone());
    let inv_sqrt = DMatrix::from_diagonal(
        &eig.eigenvalues
            .map(|v| 1.0 / v.max(mean_var * RIDGE).sqrt()),
    );
    let whiten = &eig.eigenvectors * inv_sqrt * eig.eigenvectors.transpose();
    let canonical = SymmetricEigen::new(&whiten * h * &whiten);
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&a, &b| canonical.eigenvalues[b].total_cmp(&canonical.eigenvalues[a]));
    let found = order
        .into_iter()
        .map(|i| &whiten * canonical.eigenvectors.column(i))
        .collect();
    (found, shrunk)
}

/// The paired takes of a session and their block structure.
struct Design {
    /// Indices (into the caller's takes) of the takes in a sentence spoken in two emotions.
    rows: Vec<usize>,
    sentence: Vec<usize>,
    emotion: Vec<usize>,
    sentences: usize,
    emotions: Vec<String>,
    blocks: Blocks,
}

impl Design {
    fn new(takes: &[BasisTake<'_>]) -> Option<Design> {
        let mut emotions_of: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
        for t in takes {
            let e = emotions_of.entry(t.sentence).or_default();
            if !e.contains(&t.emotion) {
                e.push(t.emotion);
            }
        }
        let rows: Vec<usize> = (0..takes.len())
            .filter(|&r| emotions_of[takes[r].sentence].len() >= 2)
            .collect();
        let (mut sentence_names, mut emotion_names): (Vec<String>, Vec<String>) = (vec![], vec![]);
        let index = |names: &mut Vec<String>, name: &str| match names.iter().position(|n| n == name)
        {
            Some(i) => i,
            None => {
                names.push(name.to_string());
                names.len() - 1
            }
        };
        let (mut sentence, mut emotion) = (Vec::new(), Vec::new());
        for &r in &rows {
            sentence.push(index(&mut sentence_names, takes[r].sentence));
            emotion.push(index(&mut emotion_names, takes[r].emotion));
        }
        let (n, s, e) = (rows.len(), sentence_names.len(), emotion_names.len());
        if e < 2 || n < s + e {
            return None;
        }
        Some(Design {
            blocks: Blocks::new(sentence.clone(), emotion.clone(), s, e),
            rows,
            sentence,
            emotion,
            sentences: s,
            emotions: emotion_names,
        })
    }

    fn df_error(&self) -> usize {
        self.rows.len() + 1 - self.sentences - self.emotions.len()
    }

    /// Effects of every column of `y`: emotions x columns (the first emotion's row 0) and
    /// sentences x columns.
    fn fit(&self, y: &DMatrix<f64>) -> Option<(DMatrix<f64>, DMatrix<f64>)> {
        let (e, s) = (self.emotions.len(), self.sentences);
        let mut beta = DMatrix::zeros(e, y.ncols());
        let mut alpha = DMatrix::zeros(s, y.ncols());
        for k in 0..y.ncols() {
            let col: Vec<f64> = y.column(k).iter().copied().collect();
            let (be, al) = self.blocks.effects(&col)?;
            beta.set_column(k, &DVector::from_vec(be));
            alpha.set_column(k, &DVector::from_vec(al));
        }
        Some((beta, alpha))
    }

    /// The emotion effects of `y`'s columns, centred over the takes.
    fn effects(&self, y: &DMatrix<f64>) -> Option<DMatrix<f64>> {
        let (mut beta, _) = self.fit(y)?;
        let n = self.rows.len() as f64;
        for k in 0..beta.ncols() {
            let mean: f64 = self.emotion.iter().map(|&e| beta[(e, k)]).sum::<f64>() / n;
            beta.column_mut(k).add_scalar_mut(-mean);
        }
        Some(beta)
    }

    /// Residuals of the full additive fit, of sentences alone and of emotions alone.
    fn residuals(&self, y: &DMatrix<f64>) -> Option<[DMatrix<f64>; 3]> {
        let (beta, alpha) = self.fit(y)?;
        let group = |labels: &[usize], groups: usize| {
            let mut sum = DMatrix::<f64>::zeros(groups, y.ncols());
            let mut count = vec![0.0; groups];
            for (r, &g) in labels.iter().enumerate() {
                let row = sum.row(g) + y.row(r);
                sum.set_row(g, &row);
                count[g] += 1.0;
            }
            DMatrix::from_fn(y.nrows(), y.ncols(), |r, k| {
                y[(r, k)] - sum[(labels[r], k)] / count[labels[r]]
            })
        };
        let full = DMatrix::from_fn(y.nrows(), y.ncols(), |r, k| {
            y[(r, k)] - alpha[(self.sentence[r], k)] - beta[(self.emotion[r], k)]
        });
        Some([
            full,
            group(&self.sentence, self.sentences),
            group(&self.emotion, self.emotions.len()),
        ])
    }

    /// Hypothesis (emotions after sentences) and error SSCP matrices of `y`.
    fn sscp(&self, y: &DMatrix<f64>) -> Option<(DMatrix<f64>, DMatrix<f64>)> {
        let [full, sentences, _] = self.residuals(y)?;
        let e = full.transpose() * &full;
        Some((sentences.transpose() * &sentences - &e, e))
    }

    /// The generalised least-squares readout `(Lᵀ C⁻¹ L)⁻¹ Lᵀ C⁻¹` (d x m) of positions along
    /// `along` (m x d) from takes' `means`, `C` their within-emotion covariance (shrunk).
    fn readout(&self, means: &DMatrix<f64>, along: &DMatrix<f64>) -> Option<DMatrix<f64>> {
        let [_, _, within] = self.residuals(means)?;
        let df = self.rows.len().saturating_sub(self.emotions.len()).max(1);
        let c = shrunk(within.transpose() * &within / df as f64, df);
        let c_inv_l = c.cholesky()?.solve(along);
        let normal = along.transpose() * &c_inv_l;
        Some(normal.try_inverse()? * c_inv_l.transpose())
    }

    /// F test of the emotions on one series of take values.
    fn f_test(&self, y: &DVector<f64>) -> Option<(f64, f64)> {
        let fits = self.blocks.fit(y.as_slice())?;
        let df_effect = (self.emotions.len() - 1) as f64;
        let df = self.df_error() as f64;
        let error = fits.full / df;
        let f = if error > 0.0 {
            (fits.sentences - fits.full).max(0.0) / df_effect / error
        } else {
            f64::INFINITY
        };
        Some((f, f_upper_tail(f, df_effect, df)))
    }

    /// In the space's coordinates `z` (the takes' means): each emotion's point (emotions x d),
    /// the turn that makes both the covariance of the takes' positions about their emotion's
    /// point (`Σ_s + Σ_ε`) and the covariance of what does not persist (`own`) diagonal, and
    /// the persistence of each turned axis, `1 − own / total`. `beta` holds the emotion effects
    /// (emotions x d).
    fn space(
        &self,
        z: &DMatrix<f64>,
        beta: &DMatrix<f64>,
        own: DMatrix<f64>,
    ) -> Option<(DMatrix<f64>, DMatrix<f64>, Vec<f64>)> {
        let d = z.ncols();
        let n = self.rows.len() as f64;
        let centre = DVector::from_fn(d, |k, _| {
            (0..self.rows.len())
                .map(|r| z[(r, k)] - beta[(self.emotion[r], k)])
                .sum::<f64>()
                / n
        });
        let points = DMatrix::from_fn(beta.nrows(), d, |e, k| centre[k] + beta[(e, k)]);
        let [full, _, emotions] = self.residuals(z)?;
        let df = self.df_error() as f64;
        let take = full.transpose() * &full / df;
        let per_sentence = n / self.sentences as f64;
        let sentence = if self.sentences > 1 {
            let ms = (emotions.transpose() * &emotions - full.transpose() * &full)
                / (self.sentences - 1) as f64;
            clamp_psd((ms - &take) / per_sentence)
        } else {
            DMatrix::zeros(d, d)
        };
        let mut total = &sentence + &take;
        let ridge = RIDGE * total.trace().max(f64::MIN_POSITIVE);
        for i in 0..d {
            total[(i, i)] += ridge;
        }
        let whiten = total.cholesky()?.l().try_inverse()?;
        let eig = SymmetricEigen::new(&whiten * own * whiten.transpose());
        let turn = eig.eigenvectors.transpose() * whiten;
        let persistence = eig
            .eigenvalues
            .iter()
            .map(|v| (1.0 - v).clamp(0.0, 1.0))
            .collect();
        Some((points, turn, persistence))
    }
}

/// The nearest positive semi-definite matrix (negative eigenvalues set to 0).
fn clamp_psd(a: DMatrix<f64>) -> DMatrix<f64> {
    let sym = (&a + a.transpose()) * 0.5;
    let eig = SymmetricEigen::new(sym);
    let v = &eig.eigenvectors;
    let l = DMatrix::from_diagonal(&eig.eigenvalues.map(|x| x.max(0.0)));
    v * l * v.transpose()
}

#[cfg(test)]
#[path = "basis_tests.rs"]
mod tests;
