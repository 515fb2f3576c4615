//! The shapes a field of the face is drawn with: which markers it takes (by label), smooth
//! steps and falloffs around a centre, a side, a mouth-corner share. The expression fields
//! ([`super::expressions`]) and the mixing matrix's fields ([`super::mixing`]) both use them.

use super::geometry::{Marker, MOUTH_HALF_WIDTH};

pub(super) fn label_starts(m: &Marker, stem: &str) -> bool {
    m.kind.starts_with(stem)
}

/// Smooth step from 0 at `a` to 1 at `b`.
pub(super) fn smoothstep(a: f64, b: f64, x: f64) -> f64 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Smooth falloff around the nearer of the two mirrored centres (±cx, cy): a compact Wendland
/// C2 kernel reaching zero at 3 x `radius`, so a field never leaks onto distant regions.
pub(super) fn bump(m: &Marker, cx: f64, cy: f64, radius: f64) -> f64 {
    let (x, y) = (m.canonical[0].abs(), m.canonical[1]);
    let q = ((x - cx).powi(2) + (y - cy).powi(2)).sqrt() / (3.0 * radius);
    if q >= 1.0 {
        0.0
    } else {
        (1.0 - q).powi(4) * (4.0 * q + 1.0)
    }
}

pub(super) fn side(m: &Marker) -> f64 {
    m.canonical[0].signum()
}

/// Weight of the mouth-corner motion carried by a lip marker (1 at the corner, 0 mid-lip).
pub(super) fn corner_share(m: &Marker) -> f64 {
    (m.canonical[0].abs() / MOUTH_HALF_WIDTH).powi(2)
}
