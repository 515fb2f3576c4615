//! The spread effects of a session variant ([`super::variation`], issue 34): each emotion
//! direction also moves the speech, brow and lid fields, and a smooth non-rigid field over the
//! whole face, so that no emotion is aligned with one source or one region.

use std::f64::consts::PI;

use rand::Rng;

use super::columns::SourceLayout;
use super::geometry::{FaceGeometry, Region};
use super::seeds::{sub_rng, Stream};

/// RMS over the face markers of the face-wide field a spread effect of strength 1 adds to an
/// emotion direction, mm per unit level.
pub const SPREAD_FIELD_MM: f64 = 1.5;
/// Largest shift of a speech or brow source per unit emotion level at strength 1.
const SPREAD_SHIFT: f64 = 0.3;
/// Smooth bumps making up a face-wide field.
const SPREAD_BUMPS: usize = 6;

/// Adds the spread effects of `strength` to the emotion columns of the mixing matrix `m`
/// (channels x `layout.count()`, row-major): each direction also moves the speech, brow and
/// lid fields by a random shift per unit level, and a smooth random field over the whole
/// face ([`SPREAD_FIELD_MM`] RMS at strength 1). Head-reference markers stay still.
pub(crate) fn add_spread_effects(
    m: &mut [f64],
    face: &FaceGeometry,
    layout: SourceLayout,
    seed: u64,
    strength: f64,
) {
    let count = layout.count();
    let others: Vec<usize> = (0..layout.speech_count())
        .chain([layout.brow_raise(), layout.blink()])
        .collect();
    let face_markers: Vec<usize> = (0..face.markers.len())
        .filter(|&i| face.markers[i].region != Region::HeadReference)
        .collect();
    for d in 0..layout.emotion_dims() {
        let mut rng = sub_rng(seed, Stream::Spread, d as u64, 0);
        let shifts: Vec<f64> = others
            .iter()
            .map(|&c| {
                let shift = rng.random_range(-SPREAD_SHIFT..SPREAD_SHIFT);
                // The blink field closes the lids at 1: a quarter of the shift keeps the lids
                // from half closing for a whole take.
                if c == layout.blink() {
                    0.25 * shift.abs()
                } else {
                    shift
                }
            })
            .collect();
        let field = face_field(face, &face_markers, &mut rng);
        let col = layout.emotion(d);
        for &i in &face_markers {
            for a in 0..3 {
                let row = (i * 3 + a) * count;
                let moved: f64 = others
                    .iter()
                    .zip(&shifts)
                    .map(|(&c, s)| s * m[row + c])
                    .sum();
                m[row + col] += strength * (moved + field[i * 3 + a]);
            }
        }
    }
}

/// A smooth random displacement field over the face: a random affine field (a tilt of the
/// whole face, so every region moves) plus a few Gaussian bumps at random markers, each with
/// its own direction, scaled to [`SPREAD_FIELD_MM`] RMS over `markers`.
fn face_field(face: &FaceGeometry, markers: &[usize], rng: &mut impl Rng) -> Vec<f64> {
    let mut field = vec![0.0; face.markers.len() * 3];
    let affine: Vec<f64> = (0..12).map(|_| rng.random_range(-1.0..1.0)).collect();
    for &i in markers {
        let c = face.markers[i].canonical;
        for a in 0..3 {
            let row = &affine[a * 4..a * 4 + 4];
            field[i * 3 + a] =
                0.5 * row[0] + (row[1] * c[0] + row[2] * c[1] + row[3] * c[2]) / 100.0;
        }
    }
    for _ in 0..SPREAD_BUMPS {
        let centre = face.markers[markers[rng.random_range(0..markers.len())]].canonical;
        let radius: f64 = rng.random_range(15.0..35.0);
        let (theta, phi) = (
            rng.random_range(0.0..2.0 * PI),
            rng.random_range(-1.0f64..1.0),
        );
        let r = (1.0 - phi * phi).sqrt();
        let dir = [r * theta.cos(), r * theta.sin(), phi];
        for &i in markers {
            let c = face.markers[i].canonical;
            let d2 = (c[0] - centre[0]).powi(2) + (c[1] - centre[1]).powi(2);
            let w = (-d2 / (2.0 * radius * radius)).exp();
            for a in 0..3 {
                field[i * 3 + a] += w * dir[a];
            }
        }
    }
    remove_rigid(face, markers, &mut field);
    let ss: f64 = markers
        .iter()
        .map(|&i| (0..3).map(|a| field[i * 3 + a].powi(2)).sum::<f64>())
        .sum();
    let rms = (ss / markers.len().max(1) as f64).sqrt();
    if rms > 0.0 {
        for v in &mut field {
            *v *= SPREAD_FIELD_MM / rms;
        }
    }
    field
}

/// Removes from `field` its least-squares rigid part over `markers` (a translation and a small
/// rotation about their centroid): an emotion moves the face, not the head, and a rigid part
/// would be taken for head motion by any stabilisation.
///
/// About the centroid the two parts separate: the translation is the mean displacement, and the
/// rotation `ω` solves `(Σ |r|² I − r rᵀ) ω = Σ r × (f − t)`.
fn remove_rigid(face: &FaceGeometry, markers: &[usize], field: &mut [f64]) {
    let n = markers.len().max(1) as f64;
    let (mut centre, mut t) = ([0.0; 3], [0.0; 3]);
    for &i in markers {
        for a in 0..3 {
            centre[a] += face.markers[i].canonical[a] / n;
            t[a] += field[i * 3 + a] / n;
        }
    }
    let arm = |i: usize| -> [f64; 3] {
        std::array::from_fn(|a| face.markers[i].canonical[a] - centre[a])
    };
    let mut inertia = [[0.0; 3]; 3];
    let mut torque = [0.0; 3];
    for &i in markers {
        let r = arm(i);
        let f: [f64; 3] = std::array::from_fn(|a| field[i * 3 + a] - t[a]);
        let rr = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
        for j in 0..3 {
            for k in 0..3 {
                inertia[j][k] += if j == k { rr } else { 0.0 } - r[j] * r[k];
            }
        }
        let c = cross(r, f);
        for j in 0..3 {
            torque[j] += c[j];
        }
    }
    let omega = solve3(inertia, torque).unwrap_or([0.0; 3]);
    for &i in markers {
        let spin = cross(omega, arm(i));
        for a in 0..3 {
            field[i * 3 + a] -= t[a] + spin[a];
        }
    }
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `m x = y` by Cramer's rule; `None` for a singular `m`.
fn solve3(m: [[f64; 3]; 3], y: [f64; 3]) -> Option<[f64; 3]> {
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(m);
    if d.abs() < 1e-12 {
        return None;
    }
    Some(std::array::from_fn(|c| {
        let mut mc = m;
        for r in 0..3 {
            mc[r][c] = y[r];
        }
        det(mc) / d
    }))
}

#[cfg(test)]
mod tests;
