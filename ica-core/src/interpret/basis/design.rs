//! The paired takes of a session as a block design (sentence x emotion), and the fits over it
//! that [`super::emotion_basis`] composes.

use std::collections::BTreeMap;

use nalgebra::{DMatrix, DVector, SymmetricEigen};

use super::{shrunk, BasisTake, RIDGE};
use crate::interpret::anova::Blocks;
use crate::interpret::effect::f_upper_tail;

/// The paired takes of a session and their block structure.
pub(super) struct Design {
    /// Indices (into the caller's takes) of the takes in a sentence spoken in two emotions.
    pub(super) rows: Vec<usize>,
    pub(super) sentence: Vec<usize>,
    pub(super) emotion: Vec<usize>,
    pub(super) sentences: usize,
    pub(super) emotions: Vec<String>,
    pub(super) blocks: Blocks,
}

impl Design {
    pub(super) fn new(takes: &[BasisTake<'_>]) -> Option<Design> {
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

    pub(super) fn df_error(&self) -> usize {
        self.rows.len() + 1 - self.sentences - self.emotions.len()
    }

    /// Effects of every column of `y`: emotions x columns (the first emotion's row 0) and
    /// sentences x columns.
    pub(super) fn fit(&self, y: &DMatrix<f64>) -> Option<(DMatrix<f64>, DMatrix<f64>)> {
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
    pub(super) fn effects(&self, y: &DMatrix<f64>) -> Option<DMatrix<f64>> {
        let (mut beta, _) = self.fit(y)?;
        let n = self.rows.len() as f64;
        for k in 0..beta.ncols() {
            let mean: f64 = self.emotion.iter().map(|&e| beta[(e, k)]).sum::<f64>() / n;
            beta.column_mut(k).add_scalar_mut(-mean);
        }
        Some(beta)
    }

    /// Residuals of the full additive fit, of sentences alone and of emotions alone.
    pub(super) fn residuals(&self, y: &DMatrix<f64>) -> Option<[DMatrix<f64>; 3]> {
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
    pub(super) fn sscp(&self, y: &DMatrix<f64>) -> Option<(DMatrix<f64>, DMatrix<f64>)> {
        let [full, sentences, _] = self.residuals(y)?;
        let e = full.transpose() * &full;
        Some((sentences.transpose() * &sentences - &e, e))
    }

    /// The generalised least-squares readout `(Lᵀ C⁻¹ L)⁻¹ Lᵀ C⁻¹` (d x m) of positions along
    /// `along` (m x d) from takes' `means`, `C` their within-emotion covariance (shrunk).
    pub(super) fn readout(
        &self,
        means: &DMatrix<f64>,
        along: &DMatrix<f64>,
    ) -> Option<DMatrix<f64>> {
        let [_, _, within] = self.residuals(means)?;
        let df = self.rows.len().saturating_sub(self.emotions.len()).max(1);
        let c = shrunk(within.transpose() * &within / df as f64, df);
        let c_inv_l = c.cholesky()?.solve(along);
        let normal = along.transpose() * &c_inv_l;
        Some(normal.try_inverse()? * c_inv_l.transpose())
    }

    /// F test of the emotions on one series of take values.
    pub(super) fn f_test(&self, y: &DVector<f64>) -> Option<(f64, f64)> {
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
    pub(super) fn space(
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
