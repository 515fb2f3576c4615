//! Head stabilisation: remove each frame's rigid head motion before modelling the face, and put
//! it back after editing.
//!
//! A set of rigid reference markers (forehead, nose bridge, head band...) is chosen by label or
//! found in the capture ([`search`]: markers rigid among themselves that move as a head, not as
//! a part of the face; [`GroupAssessment`] says how well). From the
//! training frames a reference shape, the *template*, is built by generalised Procrustes
//! averaging. Each frame's pose is then the rigid transform (Kabsch) that best maps the template
//! onto the reference markers present in that frame: `world = R · head + t`.
//!
//! Per frame everything is stack-allocated (3 x 3 SVD), so [`Stabiliser::estimate`] and the two
//! transforms are allocation-free. At least three present reference markers are needed; with
//! fewer the last pose is held and the frame is flagged.

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

mod assess;
mod pairs;
mod rotation;
mod sample;
pub mod search;
mod transform;

pub use assess::{GroupAssessment, MIN_MOTION_MM, MOTION_FACTOR};
pub use sample::{MarkerFrames, TakeFrames};
pub use search::{assess_named, choose, search_reference, Choice, ReferenceSearch, SearchParams};
pub use transform::{to_head_into, to_world_into};

/// Why stabilisation could not be set up.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StabiliseError {
    /// Fewer than three reference markers were given or found.
    #[error("head stabilisation needs at least 3 reference markers, got {0}")]
    TooFewReferences(usize),
    /// A reference marker index is out of range.
    #[error("reference marker {index} out of range for {markers} markers")]
    BadIndex {
        /// The index given.
        index: usize,
        /// Markers in a frame.
        markers: usize,
    },
    /// No training frame shows at least three reference markers.
    #[error("no frame shows at least 3 of the reference markers")]
    NoUsableFrame,
    /// The reference markers are (nearly) collinear, so rotation is undetermined.
    #[error("reference markers are collinear: rotation about their line is undetermined")]
    Degenerate,
}

/// The stored stabilisation: which markers are rigid and their shape in head coordinates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeadReference {
    /// Marker indices (into the model's labels) of the rigid reference markers.
    pub markers: Vec<usize>,
    /// The reference shape in head coordinates (mm), one point per reference marker, centred.
    pub template: Vec<[f64; 3]>,
}

/// A frame's rigid head pose: `world = rotation · head + translation`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Rotation from head to world coordinates.
    pub rotation: Matrix3<f64>,
    /// Translation from head to world coordinates (mm).
    pub translation: Vector3<f64>,
}

impl Pose {
    /// The identity pose.
    pub fn identity() -> Pose {
        Pose {
            rotation: Matrix3::identity(),
            translation: Vector3::zeros(),
        }
    }
}

/// What [`Stabiliser::estimate`] found for one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseEstimate {
    /// The pose used for the frame.
    pub pose: Pose,
    /// RMS distance (mm) between the posed template and the observed reference markers.
    pub residual_mm: f64,
    /// Reference markers present in the frame.
    pub used: usize,
    /// True when fewer than three reference markers were present and the last pose was held.
    pub held: bool,
}

/// Kabsch fit of `template` points onto `observed` points (pairs where `present`), minimising the
/// squared distances. Returns `None` with fewer than three pairs or a degenerate configuration.
/// The rotation comes from [`rotation::best_rotation`].
pub(crate) fn kabsch<'a>(
    pairs: impl Iterator<Item = (&'a [f64; 3], Vector3<f64>)> + Clone,
) -> Option<(Pose, usize)> {
    let mut count = 0usize;
    let mut p_mean = Vector3::zeros();
    let mut q_mean = Vector3::zeros();
    for (p, q) in pairs.clone() {
        p_mean += Vector3::from(*p);
        q_mean += q;
        count += 1;
    }
    if count < 3 {
        return None;
    }
    p_mean /= count as f64;
    q_mean /= count as f64;
    let mut h = Matrix3::zeros();
    let mut norms = 0.0;
    for (p, q) in pairs {
        let (p, q) = (Vector3::from(*p) - p_mean, q - q_mean);
        h += p * q.transpose();
        norms += p.norm_squared() + q.norm_squared();
    }
    let rotation = rotation::best_rotation(&h, norms)?;
    let translation = q_mean - rotation * p_mean;
    Some((
        Pose {
            rotation,
            translation,
        },
        count,
    ))
}

pub(crate) fn point(frame: &[f32], marker: usize) -> Vector3<f64> {
    let i = marker * 3;
    Vector3::new(frame[i] as f64, frame[i + 1] as f64, frame[i + 2] as f64)
}

/// Per-frame stabiliser built from a [`HeadReference`].
#[derive(Debug, Clone)]
pub struct Stabiliser {
    reference: HeadReference,
    last: Pose,
}

impl Stabiliser {
    /// A stabiliser for a stored reference.
    ///
    /// # Errors
    /// [`StabiliseError::TooFewReferences`] when the reference has fewer than three markers.
    pub fn new(reference: HeadReference) -> Result<Stabiliser, StabiliseError> {
        if reference.markers.len() < 3 || reference.template.len() != reference.markers.len() {
            return Err(StabiliseError::TooFewReferences(reference.markers.len()));
        }
        Ok(Stabiliser {
            reference,
            last: Pose::identity(),
        })
    }

    /// Builds the template from training frames by generalised Procrustes averaging.
    ///
    /// `frames` is frames x markers x 3 (mm), `missing` frames x markers.
    ///
    /// # Errors
    /// Too few or out-of-range reference markers, no usable frame, collinear references.
    pub fn fit(
        frames: &[f32],
        missing: &[bool],
        n_markers: usize,
        markers: Vec<usize>,
    ) -> Result<Stabiliser, StabiliseError> {
        if markers.len() < 3 {
            return Err(StabiliseError::TooFewReferences(markers.len()));
        }
        if let Some(&index) = markers.iter().find(|&&i| i >= n_markers) {
            return Err(StabiliseError::BadIndex {
                index,
                markers: n_markers,
            });
        }
        let n_frames = missing.len() / n_markers.max(1);
        let complete = |f: usize| markers.iter().all(|&m| !missing[f * n_markers + m]);
        let first = (0..n_frames)
            .find(|&f| complete(f))
            .ok_or(StabiliseError::NoUsableFrame)?;
        let frame_of = |f: usize| &frames[f * n_markers * 3..(f + 1) * n_markers * 3];
        let mut template: Vec<[f64; 3]> = markers
            .iter()
            .map(|&m| point(frame_of(first), m).into())
            .collect();
        centre(&mut template);
        for _ in 0..3 {
            let mut sum = vec![Vector3::<f64>::zeros(); markers.len()];
            let mut count = vec![0usize; markers.len()];
            // Every frame's pose at once on the current rayon pool, then summed in frame
            // order, so the template does not depend on the thread count.
            let poses: Vec<Option<Pose>> = (0..n_frames)
                .into_par_iter()
                .map(|f| {
                    let frame = frame_of(f);
                    let pairs = (0..markers.len())
                        .filter(|&k| !missing[f * n_markers + markers[k]])
                        .map(|k| (&template[k], point(frame, markers[k])));
                    kabsch(pairs).map(|(pose, _)| pose)
                })
                .collect();
            for (f, pose) in poses.iter().enumerate() {
                let frame = frame_of(f);
                let present = |k: &usize| !missing[f * n_markers + markers[*k]];
                let Some(pose) = pose else {
                    continue;
                };
                let inv = pose.rotation.transpose();
                for k in (0..markers.len()).filter(present) {
                    sum[k] += inv * (point(frame, markers[k]) - pose.translation);
                    count[k] += 1;
                }
            }
            for k in 0..markers.len() {
                if count[k] > 0 {
                    template[k] = (sum[k] / count[k] as f64).into();
                }
            }
            centre(&mut template);
        }
        let reference = HeadReference { markers, template };
        // A template whose own points are collinear cannot fix a rotation.
        let own = reference.template.iter().map(|p| (p, Vector3::from(*p)));
        kabsch(own).ok_or(StabiliseError::Degenerate)?;
        Stabiliser::new(reference)
    }

    /// The stored reference (for the model file).
    pub fn reference(&self) -> &HeadReference {
        &self.reference
    }

    /// Estimates the head pose of one frame (markers x 3, mm). Allocation-free.
    ///
    /// With fewer than three present reference markers the previous pose is held.
    pub fn estimate(&mut self, frame: &[f32], missing: &[bool]) -> PoseEstimate {
        let r = &self.reference;
        let pairs = r
            .markers
            .iter()
            .zip(&r.template)
            .filter(|(&m, _)| !missing[m])
            .map(|(&m, p)| (p, point(frame, m)));
        match kabsch(pairs.clone()) {
            Some((pose, used)) => {
                let sq: f64 = pairs
                    .map(|(p, q)| {
                        (pose.rotation * Vector3::from(*p) + pose.translation - q).norm_squared()
                    })
                    .sum();
                self.last = pose;
                PoseEstimate {
                    pose,
                    residual_mm: (sq / used as f64).sqrt(),
                    used,
                    held: false,
                }
            }
            None => PoseEstimate {
                pose: self.last,
                residual_mm: f64::NAN,
                used: r.markers.iter().filter(|&&m| !missing[m]).count(),
                held: true,
            },
        }
    }

    /// Forgets the held pose (e.g. at the start of a new take).
    pub fn reset(&mut self) {
        self.last = Pose::identity();
    }
}

pub(crate) fn centre(points: &mut [[f64; 3]]) {
    let n = points.len().max(1) as f64;
    let mut mean = [0.0; 3];
    for p in points.iter() {
        for a in 0..3 {
            mean[a] += p[a] / n;
        }
    }
    for p in points.iter_mut() {
        for a in 0..3 {
            p[a] -= mean[a];
        }
    }
}

#[cfg(test)]
mod tests;
