//! How good a set of markers is as a head reference, measured on a sample of the capture.
//!
//! - **Deformation**: the fiducial localisation error (FLE), the RMS distance between each
//!   marker and the rigid fit of the group's template, corrected for the fit's own degrees of
//!   freedom (`E FRE² = (1 − 2/N) FLE²`, Fitzpatrick, West & Maurer 1998). The worst 1 % of
//!   frames are left out (glitches the speed check missed).
//! - **Pose error at the face**: the target registration error of the same paper,
//!   `TRE²(r) = FLE²/N · (1 + ⅓ Σ_k d_k²/f_k²)` (`d_k` the target's distance from the group's
//!   principal axis `k`, `f_k` the group's RMS distance from it), averaged over the other
//!   markers: how far stabilisation will misplace the face, frame by frame.
//! - **Head motion**: the RMS world motion of head-fixed points at the face markers' places.
//! - **Leakage**: in the group's own coordinates, the median share of another marker's motion
//!   that the group's pose explains. A true head leaves the face's expression alone (low); a
//!   forehead lifting with the brows pushes its own motion, inverted, onto every other marker
//!   (high).

use nalgebra::{Matrix3, SVector, SymmetricEigen, Vector3};
use rayon::prelude::*;

use super::sample::Sample;
use super::{centre, kabsch, point, Pose};
use crate::robust::median;
use leakage::{explained_share, explained_with, PoseGram};

mod leakage;

/// Head motion counts as measurable when it moves the face by more than this many times the
/// pose error the reference itself would add...
pub const MOTION_FACTOR: f64 = 3.0;
/// ...and by more than this (mm RMS).
pub const MIN_MOTION_MM: f64 = 0.3;
/// Deformation (mm RMS per marker) below this multiple of the noise of one 3-D sample
/// (`√3 σ`) counts as rigid within the capture's noise (a rigid band measures 1.0x on the
/// synthetic face, its estimate varies by about 3 %; one holding an upper forehead that rises
/// 1.5 mm with the brows 1.2x to 1.3x).
pub const RIGID_NOISE_FACTOR: f64 = 1.1;

/// The assessment of one candidate reference group. See the module docs.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupAssessment {
    /// Marker indices, ascending.
    pub markers: Vec<usize>,
    /// Deformation of the group (FLE), mm RMS per marker.
    pub deformation_mm: f64,
    /// Each marker's RMS distance from its place in the fitted template (mm), group order.
    pub marker_residual_mm: Vec<f64>,
    /// Whether the deformation is within the capture's noise.
    pub rigid: bool,
    /// Head motion at the face, mm RMS.
    pub motion_mm: f64,
    /// Expected pose error at the face (TRE), mm RMS.
    pub pose_error_mm: f64,
    /// Median share of the other markers' motion the group's pose explains, 0..1.
    pub leakage: f64,

    /// The capture's noise per coordinate, mm.
    pub noise_mm: f64,
    /// The group's shape (centred, mm, group order) by generalised Procrustes averaging over
    /// the sample: the head reference's template when the group is chosen.
    pub template: Vec<[f64; 3]>,
}

impl GroupAssessment {
    /// Whether the head moves enough for stabilising on this group to pay: more than
    /// [`MOTION_FACTOR`] × the pose error it adds, and more than [`MIN_MOTION_MM`].
    pub fn motion_is_measurable(&self) -> bool {
        self.motion_mm > MOTION_FACTOR * self.pose_error_mm && self.motion_mm > MIN_MOTION_MM
    }
}

/// What an assessment reads: the sample's frames it fits (storage indices of triple centres)
/// and the markers it measures the face by.
pub(crate) struct Scope<'a> {
    pub(crate) frames: &'a [usize],
    pub(crate) others: &'a [usize],
}

/// The group's pose in every fitted frame, with the fit's residuals.
struct Fits {
    /// Storage index of each fitted frame.
    frames: Vec<usize>,
    poses: Vec<Pose>,
    /// Mean squared residual per fitted frame.
    residual_sq: Vec<f64>,
    /// Squared residual of each group marker per fitted frame (NaN when absent), frame-major.
    per_marker_sq: Vec<f64>,
}

/// Assesses `group` as a head reference over `scope` (the `others`: markers present enough,
/// the group's own left out by the caller or here); `None` when fewer than three of its
/// markers are ever seen together or they are collinear.
pub(crate) fn assess_group(
    sample: &Sample,
    group: &[usize],
    scope: &Scope<'_>,
    noise_mm: f64,
) -> Option<GroupAssessment> {
    let template = template(sample, group, scope.frames)?;
    let others: Vec<usize> = scope
        .others
        .iter()
        .copied()
        .filter(|m| !group.contains(m))
        .collect();
    let fits = fit_all(sample, group, &template, scope.frames);
    if fits.frames.is_empty() {
        return None;
    }
    let k = group.len();
    let marker_residual_mm = (0..k)
        .map(|j| {
            let (sum, count) = fits
                .per_marker_sq
                .iter()
                .skip(j)
                .step_by(k)
                .filter(|v| !v.is_nan())
                .fold((0.0, 0usize), |(s, c), v| (s + v, c + 1));
            (sum / count.max(1) as f64).sqrt()
        })
        .collect();
    let mut res = fits.residual_sq.clone();
    res.sort_by(f64::total_cmp);
    res.truncate(((res.len() as f64 * 0.99).ceil() as usize).max(1));
    let fre_sq = res.iter().sum::<f64>() / res.len() as f64;
    let deformation_mm = (fre_sq / (1.0 - 2.0 / k as f64).max(1.0 / 3.0)).sqrt();
    let (targets, leakage) = seen_from_head(sample, &fits, &others);
    let pose_error_mm = tre(&template, &targets, deformation_mm);
    let motion_mm = motion(&fits, &targets);
    Some(GroupAssessment {
        markers: group.to_vec(),
        marker_residual_mm,
        rigid: deformation_mm <= RIGID_NOISE_FACTOR * 3f64.sqrt() * noise_mm,
        deformation_mm,
        motion_mm,
        pose_error_mm,
        leakage,
        noise_mm,
        template,
    })
}

/// The group's shape by generalised Procrustes averaging over the sample's `frames`.
fn template(sample: &Sample, group: &[usize], frames: &[usize]) -> Option<Vec<[f64; 3]>> {
    let complete = |f: usize| group.iter().all(|&m| sample.get(f, m).is_some());
    let first = frames.iter().copied().find(|&f| complete(f))?;
    let mut template: Vec<[f64; 3]> = group
        .iter()
        .map(|&m| point(sample.get(first, m).expect("complete frame"), 0).into())
        .collect();
    centre(&mut template);
    let mut sum = vec![Vector3::<f64>::zeros(); group.len()];
    let mut count = vec![0usize; group.len()];
    for _ in 0..3 {
        sum.fill(Vector3::zeros());
        count.fill(0);
        for (&f, pose) in frames
            .iter()
            .zip(fit_each(sample, group, &template, frames))
        {
            let Some(pose) = pose else {
                continue;
            };
            let inv = pose.rotation.transpose();
            for (k, &m) in group.iter().enumerate() {
                if let Some(p) = sample.get(f, m) {
                    sum[k] += inv * (point(p, 0) - pose.translation);
                    count[k] += 1;
                }
            }
        }
        for k in 0..group.len() {
            if count[k] > 0 {
                template[k] = (sum[k] / count[k] as f64).into();
            }
        }
        centre(&mut template);
    }
    let own = template.iter().map(|p| (p, Vector3::from(*p)));
    kabsch(own).map(|_| template)
}

/// Template points paired with a frame's observed ones, reused across frames.
type Pairs = Vec<([f64; 3], Vector3<f64>)>;

/// The group's pose in frame `f` (a sample storage index).
fn fit(
    sample: &Sample,
    group: &[usize],
    template: &[[f64; 3]],
    f: usize,
    pairs: &mut Pairs,
) -> Option<Pose> {
    pairs.clear();
    for (&m, t) in group.iter().zip(template) {
        if let Some(q) = sample.get(f, m) {
            pairs.push((*t, point(q, 0)));
        }
    }
    kabsch(pairs.iter().map(|(t, q)| (t, *q))).map(|(pose, _)| pose)
}

/// The group's pose in each of `frames` (`None` where it cannot be fitted), frames at once on
/// the current rayon pool: the fits are most of an assessment, and a shortlist of a few groups
/// assessed at once would leave a core idle. Collected in order, so what the caller sums over
/// them is summed in the same order whatever the thread count.
fn fit_each(
    sample: &Sample,
    group: &[usize],
    template: &[[f64; 3]],
    frames: &[usize],
) -> Vec<Option<Pose>> {
    frames
        .par_iter()
        .map_init(
            || Pairs::with_capacity(group.len()),
            |pairs, &f| fit(sample, group, template, f, pairs),
        )
        .collect()
}

/// Poses and residuals of the group in every one of `frames` where it can be fitted.
fn fit_all(sample: &Sample, group: &[usize], template: &[[f64; 3]], frames: &[usize]) -> Fits {
    let mut fits = Fits {
        frames: Vec::with_capacity(frames.len()),
        poses: Vec::with_capacity(frames.len()),
        residual_sq: Vec::with_capacity(frames.len()),
        per_marker_sq: Vec::with_capacity(frames.len() * group.len()),
    };
    for (&f, pose) in frames.iter().zip(fit_each(sample, group, template, frames)) {
        let Some(pose) = pose else {
            continue;
        };
        let (mut sq, mut used) = (0.0, 0usize);
        for (&m, t) in group.iter().zip(template) {
            let r = match sample.get(f, m) {
                Some(q) => {
                    let r = (pose.rotation * Vector3::from(*t) + pose.translation - point(q, 0))
                        .norm_squared();
                    (sq, used) = (sq + r, used + 1);
                    r
                }
                None => f64::NAN,
            };
            fits.per_marker_sq.push(r);
        }
        fits.frames.push(f);
        fits.poses.push(pose);
        fits.residual_sq.push(sq / used as f64);
    }
    fits
}

/// Fitzpatrick's TRE averaged (RMS) over `targets`, for a group of the template's shape.
fn tre(template: &[[f64; 3]], targets: &[Vector3<f64>], fle: f64) -> f64 {
    if targets.is_empty() {
        return fle;
    }
    let n = template.len() as f64;
    let mut cov = Matrix3::zeros();
    for p in template {
        let v = Vector3::from(*p);
        cov += v * v.transpose() / n;
    }
    let eig = SymmetricEigen::new(cov);
    let total: f64 = eig.eigenvalues.sum();
    let sum_sq: f64 = targets
        .iter()
        .map(|r| {
            let ratio: f64 = (0..3)
                .map(|k| {
                    let axis = eig.eigenvectors.column(k);
                    // Squared distance from axis k: |r|² minus its part along the axis; the
                    // group's RMS squared distance from the axis: the other two variances.
                    let d2 = r.norm_squared() - r.dot(&axis).powi(2);
                    let f2 = (total - eig.eigenvalues[k]).max(1e-9);
                    d2 / f2
                })
                .sum();
            fle * fle / n * (1.0 + ratio / 3.0)
        })
        .sum();
    (sum_sq / targets.len() as f64).sqrt()
}

/// RMS world motion of head-fixed points at `targets`.
fn motion(fits: &Fits, targets: &[Vector3<f64>]) -> f64 {
    let (mut sq, mut count) = (0.0, 0usize);
    let mut world = Vec::with_capacity(fits.poses.len());
    for r in targets {
        world.clear();
        world.extend(fits.poses.iter().map(|p| p.rotation * r + p.translation));
        let mean = world.iter().sum::<Vector3<f64>>() / world.len() as f64;
        sq += world.iter().map(|w| (w - mean).norm_squared()).sum::<f64>();
        count += world.len();
    }
    (sq / count.max(1) as f64).sqrt()
}

/// Pose parameters of a frame: translation (mm) and the rotation's axis times the sine of its
/// angle, `(R − Rᵀ)/2` read as a vector (exact and free of `acos` at small angles).
fn pose_params(p: &Pose) -> SVector<f64, 6> {
    let r = &p.rotation;
    let rv = Vector3::new(
        (r[(2, 1)] - r[(1, 2)]) / 2.0,
        (r[(0, 2)] - r[(2, 0)]) / 2.0,
        (r[(1, 0)] - r[(0, 1)]) / 2.0,
    );
    SVector::<f64, 6>::from_column_slice(&[
        p.translation.x,
        p.translation.y,
        p.translation.z,
        rv.x,
        rv.y,
        rv.z,
    ])
}

/// The other markers in the group's coordinates, each in one pass over its frames: the mean
/// head-coordinate position of each (that has any), and the leakage, the median over them of
/// the share of their head-coordinate variance explained linearly by the pose parameters.
/// Markers at once on the current rayon pool (a shortlist of a few groups would keep one core
/// busy and the other idle), each into its own buffer of rows, collected in order. The pose
/// side of the regression ([`PoseGram`]) is made once for the markers seen in every fitted
/// frame, most of them: the same sums in the same order as each would make, so the same
/// shares, without a Gram matrix and its factorisation per marker.
fn seen_from_head(sample: &Sample, fits: &Fits, others: &[usize]) -> (Vec<Vector3<f64>>, f64) {
    let params: Vec<SVector<f64, 6>> = fits.poses.iter().map(pose_params).collect();
    let every_frame = PoseGram::of(params.iter().map(|p| p.push(1.0)));
    let each: Vec<(Option<Vector3<f64>>, Option<f64>)> = others
        .par_iter()
        .map_init(Vec::new, |rows, &m| {
            rows.clear();
            rows.extend(fits.frames.iter().zip(&fits.poses).zip(&params).filter_map(
                |((&f, pose), p)| {
                    let x = point(sample.get(f, m)?, 0);
                    let head = pose.rotation.transpose() * (x - pose.translation);
                    Some((p.push(1.0), head))
                },
            ));
            let mean = (!rows.is_empty())
                .then(|| rows.iter().map(|r| r.1).sum::<Vector3<f64>>() / rows.len() as f64);
            let share = if rows.len() == params.len() {
                explained_with(&every_frame, rows)
            } else {
                explained_share(rows)
            };
            (mean, share)
        })
        .collect();
    let targets = each.iter().filter_map(|e| e.0).collect();
    let mut shares: Vec<f64> = each.iter().filter_map(|e| e.1).collect();
    (targets, median(&mut shares))
}

#[cfg(test)]
mod tests;
