//! The true mixing matrix: one 3-D displacement field over the markers per source (mm per unit
//! of source), region-weighted with smooth falloff.
//!
//! Source order (columns): see [`SourceLayout`]: the four speech sources, the emotion
//! directions ([`expressions`](super::expressions)), `brow_raise`, `blink`, then six head-pose
//! columns. The head columns are the first-order (small-angle) fields of the rigid
//! motion that rendering applies exactly; head-reference markers have zero rows in every facial
//! column.

use super::columns::{SourceLayout, HEAD_COLUMNS};
use super::expressions::{soft_nose_bridge, soft_nose_side, Field, EMOTION_FIELDS};
use super::geometry::{FaceGeometry, Marker, Region, MOUTH_HALF_WIDTH, MOUTH_Y};
use super::shapes::{bump, corner_share, label_starts, side, smoothstep};

/// Pivot of head rotations (mm): roughly the top of the neck.
pub const HEAD_PIVOT: [f64; 3] = [0.0, -40.0, -90.0];
/// Hinge of the jaw (y, z in mm); the jaw rotates about the x axis through it.
const JAW_HINGE: [f64; 2] = [-15.0, -95.0];
/// Jaw rotation per unit of `jaw_open`, radians (~11 mm chin drop).
const JAW_RAD: f64 = 0.1;

/// The mixing matrix for the columns of `layout`: channels x sources, row-major
/// (`m[(marker * 3 + axis) * layout.count() + source]`), mm per source unit. With `soft_nose`
/// the nose bridge, sides and tip move a little with the brows, the upper lip and the emotion,
/// as a real nose does, so that no marker of the face is rigid.
pub fn mixing_matrix(face: &FaceGeometry, soft_nose: bool, layout: SourceLayout) -> Vec<f64> {
    let mut fields: Vec<Field> = vec![jaw_open, lip_round, lip_spread, upper_lip_raise];
    fields.extend(&EMOTION_FIELDS[..layout.emotion_dims()]);
    fields.extend([brow_raise as Field, blink]);
    debug_assert_eq!(fields.len(), layout.head());
    let count = layout.count();
    let mut m = vec![0.0; face.markers.len() * 3 * count];
    for (i, marker) in face.markers.iter().enumerate() {
        let mut cols = vec![[0.0; 3]; count];
        if marker.region != Region::HeadReference {
            for (s, field) in fields.iter().enumerate() {
                cols[s] = field(marker);
            }
            if soft_nose {
                add_soft_nose(marker, &mut cols, layout);
            }
        }
        cols[layout.head()..].copy_from_slice(&head_columns(marker.rest));
        for (s, col) in cols.iter().enumerate() {
            for (axis, v) in col.iter().enumerate() {
                m[(i * 3 + axis) * count + s] = *v;
            }
        }
    }
    m
}

/// The small nose motions of a face without rigid markers (mm per source unit): the bridge
/// wrinkles with the brows and the emotion (procerus), the tip and sides follow the upper lip.
fn add_soft_nose(m: &Marker, cols: &mut [[f64; 3]], layout: SourceLayout) {
    let add = |col: &mut [f64; 3], v: [f64; 3]| {
        for (c, d) in col.iter_mut().zip(v) {
            *c += d;
        }
    };
    match m.kind.as_str() {
        "NoseBridge" => {
            add(&mut cols[layout.brow_raise()], [0.0, 0.6, 0.0]);
            for d in 0..layout.emotion_dims() {
                add(&mut cols[layout.emotion(d)], soft_nose_bridge(d));
            }
        }
        "NoseTip" => add(&mut cols[3], [0.0, 0.6, 0.3]),
        k if k.starts_with("NoseSide") => {
            add(&mut cols[3], [0.0, 0.5, 0.1]);
            for d in 0..layout.emotion_dims() {
                add(&mut cols[layout.emotion(d)], soft_nose_side(m, d));
            }
        }
        _ => {}
    }
}

/// d/d(pose) of the rigid motion at a rest point: rotations about x, y, z through the pivot,
/// then unit translations.
fn head_columns(p: [f64; 3]) -> [[f64; 3]; HEAD_COLUMNS] {
    let r = [
        p[0] - HEAD_PIVOT[0],
        p[1] - HEAD_PIVOT[1],
        p[2] - HEAD_PIVOT[2],
    ];
    [
        [0.0, -r[2], r[1]],
        [r[2], 0.0, -r[0]],
        [-r[1], r[0], 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ]
}

fn jaw_open(m: &Marker) -> [f64; 3] {
    let w = match m.region {
        Region::Jaw => 1.0,
        Region::Mouth if label_starts(m, "LowerLip") => 0.95,
        Region::Mouth if label_starts(m, "MouthCorner") => 0.45,
        Region::Mouth => 0.1,
        Region::Cheeks => smoothstep(-30.0, -72.0, m.canonical[1]),
        _ => 0.0,
    };
    let (ry, rz) = (m.canonical[1] - JAW_HINGE[0], m.canonical[2] - JAW_HINGE[1]);
    [0.0, -rz * JAW_RAD * w, ry * JAW_RAD * w]
}

fn lip_round(m: &Marker) -> [f64; 3] {
    if m.region == Region::Mouth {
        // Pucker: lips gather towards the mouth centre and push forward.
        let dy = m.canonical[1] - MOUTH_Y;
        return [
            -0.2 * m.canonical[0],
            -0.15 * dy,
            3.0 + 2.0 * (1.0 - corner_share(m)),
        ];
    }
    let g = bump(m, MOUTH_HALF_WIDTH, MOUTH_Y, 14.0);
    [-1.5 * side(m) * g, 0.0, 1.0 * g]
}

fn lip_spread(m: &Marker) -> [f64; 3] {
    if m.region == Region::Mouth {
        // Stretch sideways, thin and flatten the lips against the teeth.
        let dy = m.canonical[1] - MOUTH_Y;
        return [0.2 * m.canonical[0], -0.08 * dy, -1.5];
    }
    let g = bump(m, MOUTH_HALF_WIDTH + 6.0, MOUTH_Y, 14.0);
    [2.0 * side(m) * g, 0.0, -0.5 * g]
}

fn upper_lip_raise(m: &Marker) -> [f64; 3] {
    let x = m.canonical[0].abs();
    match m.region {
        Region::Mouth if label_starts(m, "UpperLip") => {
            let w = (-((x - 8.0) / 10.0).powi(2)).exp();
            [0.0, 2.0 + 2.5 * w, 1.0]
        }
        Region::Mouth if label_starts(m, "MouthCorner") => [0.0, 1.0, 0.0],
        Region::Mouth => [0.0, 0.8, 0.3],
        Region::Nose if label_starts(m, "NoseAla") || label_starts(m, "NoseBase") => {
            [0.0, 1.0, 0.0]
        }
        Region::Cheeks => [0.0, 1.5 * bump(m, 28.0, -40.0, 10.0), 0.0],
        _ => [0.0; 3],
    }
}

/// Frontalis raise: whole brows up (the middle most), forehead follows, upper lids lift a bit.
fn brow_raise(m: &Marker) -> [f64; 3] {
    let x = m.canonical[0].abs();
    match m.region {
        Region::Eyebrows => [0.0, 4.0 + 1.5 * bump(m, 30.0, 22.0, 12.0), 0.5],
        Region::Forehead if m.canonical[1] < 45.0 => [0.0, 3.0, 0.2],
        Region::Forehead => [0.0, 1.5, 0.0],
        Region::Eyelids if label_starts(m, "LidUpper") => [0.0, 1.0 - 0.01 * (x - 32.0).abs(), 0.0],
        _ => [0.0; 3],
    }
}

/// Upper lids close over the eye (most at the centre), lower lids rise slightly.
fn blink(m: &Marker) -> [f64; 3] {
    match m.kind.as_str() {
        l if l.starts_with("LidUpperIn") || l.starts_with("LidUpperOut") => [0.0, -6.5, -1.5],
        l if l.starts_with("LidUpper") => [0.0, -9.0, -2.0],
        l if l.starts_with("LidLower") => [0.0, 1.5, 0.0],
        _ => [0.0; 3],
    }
}

#[cfg(test)]
mod tests;
