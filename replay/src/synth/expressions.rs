//! The emotion fields: one 3-D displacement per marker per emotion direction (mm per unit),
//! evaluated at the marker's canonical position and keyed on its anatomical kind, like every
//! other field of [`mixing`](super::mixing).
//!
//! Direction 0 is the generator's historic smile/frown field. The others follow the facial
//! action units that tell anger and sadness apart from a smile (Ekman and Friesen's FACS):
//! - direction 1, brow knit + lip press (anger): AU4 lowers the inner brows and draws them
//!   together, AU7 tightens the lids, AU23/24 press and thin the lips, AU17 lifts the chin,
//!   AU38 flares the nostrils;
//! - direction 2, inner brow raise + mouth corners down (sadness): AU1 lifts the inner brows
//!   and the middle of the forehead, the upper lids droop, AU15 pulls the mouth corners down,
//!   AU17 pushes the chin and lower lip up.
//!
//! Every field moves several regions, so no emotion is confined to one of them.

use super::geometry::{Marker, Region, MOUTH_HALF_WIDTH, MOUTH_Y};
use super::shapes::{bump, corner_share, label_starts, side, smoothstep};

/// A field: displacement of one marker per unit of its source, mm.
pub(crate) type Field = fn(&Marker) -> [f64; 3];

/// The emotion fields, one per direction, in column order.
pub(crate) const EMOTION_FIELDS: [Field; 3] = [emotion, knit_press, inner_raise];

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

/// Positive = anger: inner brows down and together, lids narrowed, lips pressed thin and
/// rolled in, chin up, nostrils flared.
fn knit_press(m: &Marker) -> [f64; 3] {
    let x = m.canonical[0].abs();
    let inner = smoothstep(54.0, 14.0, x);
    match m.region {
        // Corrugator: the inner end travels most, medially and down, and bunches forward.
        Region::Eyebrows => [-2.0 * side(m) * inner, -1.0 - 3.0 * inner, 0.6 * inner],
        // The glabella and lower mid-forehead follow the brows down.
        Region::Forehead if m.canonical[1] < 45.0 => {
            let g = smoothstep(40.0, 5.0, x);
            [-0.5 * side(m) * g, -1.2 * g, 0.0]
        }
        Region::Eyelids if label_starts(m, "LidLower") => [0.0, 1.2, 0.2],
        Region::Eyelids => [0.0, -1.0, 0.0],
        Region::Nose if label_starts(m, "NoseAla") => [1.2 * side(m), 0.3, 0.0],
        Region::Mouth => {
            // Lips close onto each other and narrow; the red of the lips rolls in.
            let c = corner_share(m);
            let dy = m.canonical[1] - MOUTH_Y;
            [
                -0.06 * m.canonical[0] - 0.6 * side(m) * c,
                -0.25 * dy - 0.5 * c,
                -1.0,
            ]
        }
        Region::Cheeks => {
            let g = bump(m, MOUTH_HALF_WIDTH + 4.0, MOUTH_Y, 10.0);
            [-0.6 * side(m) * g, 0.0, -0.3 * g]
        }
        Region::Jaw => {
            let g = bump(m, 0.0, -86.0, 10.0);
            [0.0, 1.0 * g, 0.3 * g]
        }
        _ => [0.0; 3],
    }
}

/// Positive = sadness: inner brows and mid-forehead up, upper lids down, mouth corners down
/// and out, chin boss and lower lip pushed up (pout).
fn inner_raise(m: &Marker) -> [f64; 3] {
    let x = m.canonical[0].abs();
    let inner = smoothstep(54.0, 14.0, x);
    let middle = smoothstep(40.0, 5.0, x);
    match m.region {
        // Oblique brows: the inner end rises and draws in slightly, the outer end sags.
        Region::Eyebrows => [-0.5 * side(m) * inner, 4.0 * inner - 0.6, 0.2],
        Region::Forehead if m.canonical[1] < 45.0 => [0.0, 2.0 * middle, 0.0],
        Region::Forehead => [0.0, 0.8 * middle, 0.0],
        Region::Eyelids if label_starts(m, "LidLower") => [0.0, 0.4, 0.0],
        Region::Eyelids => [0.0, -0.8, -0.2],
        Region::Mouth => {
            let c = corner_share(m);
            let pout = if label_starts(m, "LowerLip") {
                1.0 - c
            } else {
                0.0
            };
            [
                0.8 * side(m) * c,
                -0.3 - 3.0 * c + 1.0 * pout,
                -0.3 * c + 0.8 * pout,
            ]
        }
        Region::Cheeks => {
            let g = bump(m, 32.0, -66.0, 12.0);
            [0.3 * side(m) * g, -1.5 * g, 0.0]
        }
        Region::Jaw => {
            let chin = bump(m, 0.0, -88.0, 10.0);
            let corner = bump(m, 30.0, -72.0, 10.0);
            [0.0, 1.5 * chin - 1.0 * corner, 0.8 * chin]
        }
        _ => [0.0; 3],
    }
}

/// The nose bridge of a face without rigid markers, per emotion direction (procerus): up with
/// a smile, pulled down by the brow knit, still for sadness.
pub(crate) fn soft_nose_bridge(direction: usize) -> [f64; 3] {
    match direction {
        0 => [0.0, 0.5, 0.1],
        1 => [0.0, -0.6, 0.1],
        _ => [0.0; 3],
    }
}

/// The nose sides of a face without rigid markers, per emotion direction: they rise with the
/// cheeks of a smile and flare with the nostrils of anger.
pub(crate) fn soft_nose_side(m: &Marker, direction: usize) -> [f64; 3] {
    match direction {
        0 => [0.3 * side(m), 0.4, 0.0],
        1 => [0.4 * side(m), 0.1, 0.0],
        _ => [0.0; 3],
    }
}
