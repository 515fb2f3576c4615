//! The injected field: a smooth random displacement over the face, in head coordinates.

use ica_core::stabilise::Pose;
use nalgebra::Vector3;
use rand::Rng;
use replay::Take;

/// Smooth bumps added to the affine part of the field.
const BUMPS: usize = 5;

/// Each marker's mean position in head coordinates over the frames it is present in (world
/// coordinates without a head reference, where every pose is the identity); markers never
/// present sit at the origin.
pub(super) fn rest_in_head(take: &Take, poses: &[Pose]) -> Vec<[f64; 3]> {
    let n = take.n_markers();
    let mut sum = vec![Vector3::<f64>::zeros(); n];
    let mut count = vec![0usize; n];
    for (f, pose) in poses.iter().enumerate() {
        let inv = pose.rotation.transpose();
        let frame = take.frame(f);
        for m in (0..n).filter(|&m| !take.is_missing(f, m)) {
            let p = Vector3::new(
                f64::from(frame[m * 3]),
                f64::from(frame[m * 3 + 1]),
                f64::from(frame[m * 3 + 2]),
            );
            sum[m] += inv * (p - pose.translation);
            count[m] += 1;
        }
    }
    sum.iter()
        .zip(&count)
        .map(|(s, &c)| (s / c.max(1) as f64).into())
        .collect()
}

/// A smooth random field over the markers at `rest` (markers x 3 out, mm): a random affine
/// field (every part of the face moves) plus a few Gaussian bumps centred on random face
/// markers, each in its own direction, scaled to `rms_mm` RMS over the face markers (all but
/// `head`, which stay still).
pub(super) fn smooth_field(
    rest: &[[f64; 3]],
    head: &[usize],
    rms_mm: f64,
    rng: &mut impl Rng,
) -> Vec<f64> {
    let face: Vec<usize> = (0..rest.len()).filter(|m| !head.contains(m)).collect();
    let mut field = vec![0.0; rest.len() * 3];
    if face.is_empty() {
        return field;
    }
    let centre: Vector3<f64> = face
        .iter()
        .map(|&m| Vector3::from(rest[m]))
        .sum::<Vector3<f64>>()
        / face.len() as f64;
    let scale = (face
        .iter()
        .map(|&m| (Vector3::from(rest[m]) - centre).norm_squared())
        .sum::<f64>()
        / face.len() as f64)
        .sqrt()
        .max(1e-6);
    let offset = unit(rng) * 0.5;
    let gradient = [unit(rng), unit(rng), unit(rng)];
    let bumps: Vec<(Vector3<f64>, f64, Vector3<f64>)> = (0..BUMPS)
        .map(|_| {
            let at = Vector3::from(rest[face[rng.random_range(0..face.len())]]);
            (at, scale * rng.random_range(0.3..0.7), unit(rng))
        })
        .collect();
    for &m in &face {
        let x = Vector3::from(rest[m]);
        let p = (x - centre) / scale;
        let mut v = offset;
        for (a, g) in gradient.iter().enumerate() {
            v += g * p[a];
        }
        for (at, width, dir) in &bumps {
            v += dir * (-(x - at).norm_squared() / (2.0 * width * width)).exp();
        }
        field[m * 3..m * 3 + 3].copy_from_slice(v.as_slice());
    }
    remove_rigid(rest, &face, &mut field);
    let ss: f64 = field.iter().map(|v| v * v).sum();
    let rms = (ss / face.len() as f64).sqrt();
    if rms > 0.0 {
        for v in &mut field {
            *v *= rms_mm / rms;
        }
    }
    field
}

/// Removes the field's least-squares rigid part over the `face` markers (a translation and a
/// small rotation about their centroid): an expression moves the face, not the head, and a
/// rigid part would be taken for head motion by a stabilisation on face markers.
fn remove_rigid(rest: &[[f64; 3]], face: &[usize], field: &mut [f64]) {
    let n = face.len() as f64;
    let at = |m: usize| Vector3::from(rest[m]);
    let f =
        |field: &[f64], m: usize| Vector3::new(field[m * 3], field[m * 3 + 1], field[m * 3 + 2]);
    let centre = face.iter().map(|&m| at(m)).sum::<Vector3<f64>>() / n;
    let t = face.iter().map(|&m| f(field, m)).sum::<Vector3<f64>>() / n;
    // About the centroid: (Σ |r|² I − r rᵀ) ω = Σ r × (f − t).
    let mut inertia = nalgebra::Matrix3::<f64>::zeros();
    let mut torque = Vector3::<f64>::zeros();
    for &m in face {
        let r = at(m) - centre;
        inertia += nalgebra::Matrix3::identity() * r.norm_squared() - r * r.transpose();
        torque += r.cross(&(f(field, m) - t));
    }
    let omega = inertia.lu().solve(&torque).unwrap_or_else(Vector3::zeros);
    for &m in face {
        let rigid = t + omega.cross(&(at(m) - centre));
        for a in 0..3 {
            field[m * 3 + a] -= rigid[a];
        }
    }
}

/// A random unit vector.
fn unit(rng: &mut impl Rng) -> Vector3<f64> {
    let v = Vector3::<f64>::from_fn(|_, _| rng.random_range(-1.0..1.0));
    v / v.norm().max(1e-9)
}

#[cfg(test)]
mod tests;
