//! Leakage's regression (see [`super`]): the share of a face marker's head-coordinate
//! variance the group's pose parameters explain linearly, with the pose side made once and
//! shared by every marker seen in every fitted frame.

use nalgebra::{SMatrix, SVector, Vector3};

/// The pose side of [`explained_share`]'s least-squares fit over a set of rows: the rows'
/// mean and the Cholesky factor of their centred Gram matrix (intercept column kept at 1),
/// with a scale-free ridge so degenerate pose parameters (no rotation at all) stay solvable.
pub(super) struct PoseGram {
    mean_x: SVector<f64, 7>,
    factor: Option<nalgebra::Cholesky<f64, nalgebra::Const<7>>>,
}

impl PoseGram {
    /// The Gram of the rows `xs` yields.
    pub(super) fn of(xs: impl ExactSizeIterator<Item = SVector<f64, 7>> + Clone) -> Self {
        let n = xs.len() as f64;
        let mean_x = xs.clone().sum::<SVector<f64, 7>>() / n;
        let mut xtx = SMatrix::<f64, 7, 7>::zeros();
        for x in xs {
            let mut xc = x - mean_x;
            xc[6] = 1.0;
            // The upper triangle only (mirrored below): a third of the products.
            for i in 0..7 {
                for j in i..7 {
                    xtx[(i, j)] += xc[i] * xc[j];
                }
            }
        }
        for i in 0..7 {
            for j in 0..i {
                xtx[(i, j)] = xtx[(j, i)];
            }
        }
        let ridge = 1e-9 * xtx.trace().max(1e-12);
        for i in 0..7 {
            xtx[(i, i)] += ridge;
        }
        PoseGram {
            mean_x,
            factor: xtx.cholesky(),
        }
    }
}

/// Share of the variance of `y` explained by a least-squares fit on `x` (with intercept).
pub(super) fn explained_share(rows: &[(SVector<f64, 7>, Vector3<f64>)]) -> Option<f64> {
    if rows.len() < 20 {
        return None;
    }
    explained_with(&PoseGram::of(rows.iter().map(|r| r.0)), rows)
}

/// [`explained_share`] with the pose side `gram` made from the same rows' `x`.
pub(super) fn explained_with(
    gram: &PoseGram,
    rows: &[(SVector<f64, 7>, Vector3<f64>)],
) -> Option<f64> {
    if rows.len() < 20 {
        return None;
    }
    let n = rows.len() as f64;
    let mean_y = rows.iter().map(|r| r.1).sum::<Vector3<f64>>() / n;
    let mut xty = SMatrix::<f64, 7, 3>::zeros();
    let mut total = 0.0;
    for (x, y) in rows {
        let mut xc = x - gram.mean_x;
        xc[6] = 1.0;
        let yc = y - mean_y;
        for i in 0..7 {
            for a in 0..3 {
                xty[(i, a)] += xc[i] * yc[a];
            }
        }
        total += yc.norm_squared();
    }
    let beta = gram.factor.as_ref()?.solve(&xty);
    let explained: f64 = (beta.transpose() * xty).trace();
    (total > 0.0).then(|| (explained / total).clamp(0.0, 1.0))
}
