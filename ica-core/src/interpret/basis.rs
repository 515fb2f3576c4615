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

use super::effect::EMOTION_ALPHA;
use crate::model::EmotionPoint;
use design::Design;

mod design;

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
    let (kept, tests) = kept_directions(&design, &offsets, directions, m)?;
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
    basis.points = emotion_points(&design, &turn, &points, &coords);
    Some(basis)
}

/// The candidate `directions` tested strongest first, each kept while its own F test (and
/// every stronger one's) passes at [`EMOTION_ALPHA`] over the `m` components.
fn kept_directions(
    design: &Design,
    offsets: &DMatrix<f64>,
    directions: Vec<DVector<f64>>,
    m: usize,
) -> Option<(Vec<DVector<f64>>, Vec<AxisTest>)> {
    let (mut kept, mut tests) = (Vec::new(), Vec::new());
    for v in directions.into_iter().take(design.emotions.len() - 1) {
        let (f, p) = design.f_test(&(offsets * &v))?;
        let pass = tests.iter().all(|t: &AxisTest| t.kept) && p < EMOTION_ALPHA / m as f64;
        if pass {
            kept.push(v);
        }
        tests.push(AxisTest { f, p, kept: pass });
    }
    Some((kept, tests))
}

/// Each emotion's point in the turned space (`turn · (a + β_e)`), the spread of its takes'
/// positions about it, and how many takes it has.
fn emotion_points(
    design: &Design,
    turn: &DMatrix<f64>,
    points: &DMatrix<f64>,
    coords: &DMatrix<f64>,
) -> BTreeMap<String, EmotionPoint> {
    design
        .emotions
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let own: Vec<usize> = (0..coords.nrows())
                .filter(|&r| design.emotion[r] == i)
                .collect();
            let level = turn * points.row(i).transpose();
            let spread = (0..level.len())
                .map(|j| {
                    let ss: f64 = own
                        .iter()
                        .map(|&r| ((turn * coords.row(r).transpose())[j] - level[j]).powi(2))
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
        .collect()
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

#[cfg(test)]
mod tests;
