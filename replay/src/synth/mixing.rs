//! The true mixing matrix: one 3-D displacement field over the markers per source (mm per unit
//! of source), region-weighted with smooth falloff.
//!
//! Source order (columns): the four speech sources, `emotion`, `brow_raise`, `blink`, then six
//! head-pose columns. The head columns are the first-order (small-angle) fields of the rigid
//! motion that rendering applies exactly; head-reference markers have zero rows in every facial
//! column.

use serde::{Deserialize, Serialize};

use super::geometry::{FaceGeometry, Marker, Region, MOUTH_HALF_WIDTH, MOUTH_Y};
use super::speech::SPEECH_SOURCE_NAMES;

/// Number of sources (columns of the mixing matrix).
pub const SOURCE_COUNT: usize = 13;
/// Column of the emotion source.
pub const EMOTION: usize = 4;
/// Column of the eyebrow-emphasis source.
pub const BROW_RAISE: usize = 5;
/// Column of the blink source.
pub const BLINK: usize = 6;
/// First of the six head-pose columns (pitch, yaw, roll in rad; tx, ty, tz in mm).
pub const HEAD: usize = 7;
/// Pivot of head rotations (mm): roughly the top of the neck.
pub const HEAD_PIVOT: [f64; 3] = [0.0, -40.0, -90.0];
/// Hinge of the jaw (y, z in mm); the jaw rotates about the x axis through it.
const JAW_HINGE: [f64; 2] = [-15.0, -95.0];
/// Jaw rotation per unit of `jaw_open`, radians (~11 mm chin drop).
const JAW_RAD: f64 = 0.1;

/// Name and role of a source.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct SourceInfo {
    /// Source name, e.g. `jaw_open`.
    pub name: String,
    /// Role: `speech`, `emotion`, `eyebrows`, `eyelids` or `head`.
    pub role: String,
}

/// Every source, in column order.
pub fn source_infos() -> Vec<SourceInfo> {
    let mut v: Vec<(&str, &str)> = SPEECH_SOURCE_NAMES.iter().map(|n| (*n, "speech")).collect();
    v.extend([
        ("emotion", "emotion"),
        ("brow_raise", "eyebrows"),
        ("blink", "eyelids"),
    ]);
    for n in [
        "head_pitch",
        "head_yaw",
        "head_roll",
        "head_tx",
        "head_ty",
        "head_tz",
    ] {
        v.push((n, "head"));
    }
    v.into_iter()
        .map(|(n, r)| SourceInfo {
            name: n.to_string(),
            role: r.to_string(),
        })
        .collect()
}

/// The mixing matrix, channels x sources, row-major (`m[(marker * 3 + axis) * SOURCE_COUNT +
/// source]`), mm per source unit. With `soft_nose` the nose bridge, sides and tip move a
/// little with the brows, the upper lip and the emotion, as a real nose does, so that no marker
/// of the face is rigid.
pub fn mixing_matrix(face: &FaceGeometry, soft_nose: bool) -> Vec<f64> {
    let fields: [fn(&Marker) -> [f64; 3]; HEAD] = [
        jaw_open,
        lip_round,
        lip_spread,
        upper_lip_raise,
        emotion,
        brow_raise,
        blink,
    ];
    let mut m = vec![0.0; face.markers.len() * 3 * SOURCE_COUNT];
    for (i, marker) in face.markers.iter().enumerate() {
        let mut cols = [[0.0; 3]; SOURCE_COUNT];
        if marker.region != Region::HeadReference {
            for (s, field) in fields.iter().enumerate() {
                cols[s] = field(marker);
            }
            if soft_nose {
                add_soft_nose(marker, &mut cols);
            }
        }
        cols[HEAD..].copy_from_slice(&head_columns(marker.rest));
        for (s, col) in cols.iter().enumerate() {
            for (axis, v) in col.iter().enumerate() {
                m[(i * 3 + axis) * SOURCE_COUNT + s] = *v;
            }
        }
    }
    m
}

/// The small nose motions of a face without rigid markers (mm per source unit): the bridge
/// wrinkles with the brows and the emotion (procerus), the tip and sides follow the upper lip.
fn add_soft_nose(m: &Marker, cols: &mut [[f64; 3]; SOURCE_COUNT]) {
    let add = |col: &mut [f64; 3], v: [f64; 3]| {
        for (c, d) in col.iter_mut().zip(v) {
            *c += d;
        }
    };
    match m.kind.as_str() {
        "NoseBridge" => {
            add(&mut cols[BROW_RAISE], [0.0, 0.6, 0.0]);
            add(&mut cols[EMOTION], [0.0, 0.5, 0.1]);
        }
        "NoseTip" => add(&mut cols[3], [0.0, 0.6, 0.3]),
        k if k.starts_with("NoseSide") => {
            add(&mut cols[3], [0.0, 0.5, 0.1]);
            add(&mut cols[EMOTION], [0.3 * side(m), 0.4, 0.0]);
        }
        _ => {}
    }
}

/// d/d(pose) of the rigid motion at a rest point: rotations about x, y, z through the pivot,
/// then unit translations.
fn head_columns(p: [f64; 3]) -> [[f64; 3]; 6] {
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

fn label_starts(m: &Marker, stem: &str) -> bool {
    m.kind.starts_with(stem)
}

/// Smooth step from 0 at `a` to 1 at `b`.
fn smoothstep(a: f64, b: f64, x: f64) -> f64 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Smooth falloff around the nearer of the two mirrored centres (±cx, cy): a compact Wendland
/// C2 kernel reaching zero at 3 x `radius`, so a field never leaks onto distant regions.
fn bump(m: &Marker, cx: f64, cy: f64, radius: f64) -> f64 {
    let (x, y) = (m.canonical[0].abs(), m.canonical[1]);
    let q = ((x - cx).powi(2) + (y - cy).powi(2)).sqrt() / (3.0 * radius);
    if q >= 1.0 {
        0.0
    } else {
        (1.0 - q).powi(4) * (4.0 * q + 1.0)
    }
}

fn side(m: &Marker) -> f64 {
    m.canonical[0].signum()
}

/// Weight of the mouth-corner motion carried by a lip marker (1 at the corner, 0 mid-lip).
fn corner_share(m: &Marker) -> f64 {
    (m.canonical[0].abs() / MOUTH_HALF_WIDTH).powi(2)
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

/// Positive = smile (happy), negative = frown (frustrated): mouth corners, cheeks, lids and
/// brows all move, so the emotion is not confined to one region.
fn emotion(m: &Marker) -> [f64; 3] {
    let x = m.canonical[0].abs();
    let inner = smoothstep(54.0, 14.0, x);
    match m.region {
        Region::Mouth => {
            let c = corner_share(m);
            [3.0 * side(m) * c, 0.5 + 3.5 * c, -c]
        }
        Region::Cheeks => {
            let g = bump(m, 40.0, -32.0, 20.0);
            [0.8 * side(m) * g, 3.0 * g, 1.5 * g]
        }
        Region::Jaw => [0.0, 0.6 * bump(m, 40.0, -70.0, 15.0), 0.0],
        Region::Nose if label_starts(m, "NoseAla") => [0.3 * side(m), 0.8, 0.0],
        Region::Eyelids if label_starts(m, "LidLower") => [0.0, 1.5, 0.3],
        Region::Eyelids => [0.0, -0.8, 0.0],
        // Happy lifts and separates the inner brows; frustrated lowers and knits them.
        Region::Eyebrows => [1.5 * side(m) * inner, 1.0 + 1.5 * inner, 0.3],
        Region::Forehead if m.canonical[1] < 45.0 => [0.0, 0.8 * smoothstep(50.0, 10.0, x), 0.0],
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
mod tests {
    use super::*;

    fn moved(m: &[f64], marker: usize, source: usize) -> f64 {
        (0..3)
            .map(|a| m[(marker * 3 + a) * SOURCE_COUNT + source].powi(2))
            .sum::<f64>()
            .sqrt()
    }

    #[test]
    fn each_field_stays_in_its_regions() {
        let face = FaceGeometry::standard();
        let m = mixing_matrix(&face, false);
        let upper = [Region::Eyebrows, Region::Eyelids, Region::Forehead];
        for (i, mk) in face.markers.iter().enumerate() {
            for s in 0..SPEECH_SOURCE_NAMES.len() {
                if upper.contains(&mk.region) || mk.region == Region::HeadReference {
                    assert_eq!(moved(&m, i, s), 0.0, "speech {s} moves {}", mk.label);
                }
            }
            if mk.region == Region::Mouth {
                assert!(moved(&m, i, 0) > 0.5 || mk.label.starts_with("UpperLip"));
                assert!(moved(&m, i, 1) > 1.0 && moved(&m, i, 2) > 1.0);
            }
            let lid = mk.region == Region::Eyelids;
            assert_eq!(moved(&m, i, BLINK) > 0.0, lid, "blink on {}", mk.label);
            let brow = matches!(mk.region, Region::Eyebrows | Region::Forehead)
                || mk.label.starts_with("LidUpper");
            assert_eq!(moved(&m, i, BROW_RAISE) > 0.0, brow, "brow on {}", mk.label);
            let face_part = matches!(
                mk.region,
                Region::Mouth | Region::Cheeks | Region::Eyebrows | Region::Eyelids
            );
            if face_part && !mk.label.starts_with("Cheek") {
                assert!(moved(&m, i, EMOTION) > 0.3, "emotion on {}", mk.label);
            }
            if mk.region == Region::HeadReference {
                assert_eq!(moved(&m, i, EMOTION), 0.0);
            }
        }
    }
}
