//! The synthetic face: 109 labelled markers on a plausible head, in millimetres.
//!
//! Frame: right-handed, y up, z forward (out of the face, towards the camera), x towards the
//! subject's left (the viewer's right), so `...L` markers have x > 0. The origin sits between the
//! eyes at eye height, roughly on the plane of the eye corners. The face is ~140 mm wide.

use std::collections::BTreeMap;

/// Number of markers of the default face.
pub const MARKER_COUNT: usize = 109;

/// A named face region; every marker belongs to exactly one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Region {
    /// Lips and mouth corners (16 markers).
    Mouth,
    /// Chin and jaw line (14 markers).
    Jaw,
    /// Cheeks, nasolabial folds and under-eye (36 markers).
    Cheeks,
    /// Nose bridge, tip, alae, base (7 markers).
    Nose,
    /// Upper and lower eyelids (8 markers).
    Eyelids,
    /// Eyebrows (12 markers).
    Eyebrows,
    /// Forehead (12 markers).
    Forehead,
    /// Rigid head-band markers that move only with the skull (4 markers).
    HeadReference,
}

impl Region {
    /// Every region, in the order markers are laid out.
    pub const ALL: [Region; 8] = [
        Region::HeadReference,
        Region::Forehead,
        Region::Eyebrows,
        Region::Eyelids,
        Region::Nose,
        Region::Cheeks,
        Region::Mouth,
        Region::Jaw,
    ];

    /// The region's name as used in `regions.toml`.
    pub fn name(self) -> &'static str {
        match self {
            Region::Mouth => "mouth",
            Region::Jaw => "jaw",
            Region::Cheeks => "cheeks",
            Region::Nose => "nose",
            Region::Eyelids => "eyelids",
            Region::Eyebrows => "eyebrows",
            Region::Forehead => "forehead",
            Region::HeadReference => "head_reference",
        }
    }

    /// Glob patterns over labels that select exactly this region's markers.
    pub fn patterns(self) -> &'static [&'static str] {
        match self {
            Region::Mouth => &["UpperLip*", "LowerLip*", "MouthCorner*"],
            Region::Jaw => &["Jaw*", "Chin*", "Mentolabial"],
            Region::Cheeks => &["Cheek*"],
            Region::Nose => &["Nose*"],
            Region::Eyelids => &["Lid*"],
            Region::Eyebrows => &["Brow*"],
            Region::Forehead => &["Forehead*"],
            Region::HeadReference => &["Head*"],
        }
    }
}

/// One marker: label, region and rest position (mm).
#[derive(Debug, Clone, PartialEq)]
pub struct Marker {
    /// Label written to the takes, e.g. `MouthCornerL` (or `mouth_01`, `M042` in other
    /// [`Naming`](super::layout::Naming)s).
    pub label: String,
    /// The marker's anatomical name on the canonical face (`MouthCornerL`): what the source
    /// fields key on, whatever the label says.
    pub kind: String,
    /// Region the marker belongs to.
    pub region: Region,
    /// Rest (neutral) position, mm, as placed on this face.
    pub rest: [f64; 3],
    /// Position on the canonical face, mm: the source fields are evaluated here, so a face
    /// with moved markers still moves like a face.
    pub canonical: [f64; 3],
}

/// The marker set of the synthetic face.
#[derive(Debug, Clone, PartialEq)]
pub struct FaceGeometry {
    /// Markers in file order.
    pub markers: Vec<Marker>,
}

impl FaceGeometry {
    /// The default 109-marker face.
    pub fn standard() -> FaceGeometry {
        let mut b = Builder::default();
        head_reference(&mut b);
        upper_face(&mut b);
        nose(&mut b);
        cheeks(&mut b);
        mouth(&mut b);
        jaw(&mut b);
        FaceGeometry { markers: b.markers }
    }

    /// Labels in file order.
    pub fn labels(&self) -> Vec<String> {
        self.markers.iter().map(|m| m.label.clone()).collect()
    }

    /// Rest shape as a flat markers x 3 vector (mm).
    pub fn rest_flat(&self) -> Vec<f64> {
        self.markers.iter().flat_map(|m| m.rest).collect()
    }

    /// Indices of the markers in `region`.
    pub fn indices(&self, region: Region) -> Vec<usize> {
        (0..self.markers.len())
            .filter(|&i| self.markers[i].region == region)
            .collect()
    }

    /// Region name -> labels of the markers in it.
    /// Regions without markers (the head reference of a face with no rigid markers) are left
    /// out.
    pub fn region_labels(&self) -> BTreeMap<String, Vec<String>> {
        Region::ALL
            .iter()
            .filter_map(|r| {
                let labels: Vec<String> = self
                    .indices(*r)
                    .into_iter()
                    .map(|i| self.markers[i].label.clone())
                    .collect();
                (!labels.is_empty()).then(|| (r.name().to_string(), labels))
            })
            .collect()
    }

    /// Region name -> glob patterns, the content of the generated `regions.toml`.
    pub fn region_patterns() -> BTreeMap<String, Vec<String>> {
        Region::ALL
            .iter()
            .map(|r| {
                let pats = r.patterns().iter().map(|p| p.to_string()).collect();
                (r.name().to_string(), pats)
            })
            .collect()
    }
}

#[derive(Default)]
struct Builder {
    markers: Vec<Marker>,
}

impl Builder {
    /// Adds a marker on the skin surface at (x, y), raised by `dz` mm along z.
    fn skin(&mut self, label: &str, region: Region, x: f64, y: f64, dz: f64) {
        self.at(label, region, [x, y, surface_z(x, y) + dz]);
    }

    fn at(&mut self, label: &str, region: Region, rest: [f64; 3]) {
        self.markers.push(Marker {
            label: label.to_string(),
            kind: label.to_string(),
            region,
            rest,
            canonical: rest,
        });
    }

    /// Adds a left/right pair, `L` at +x, from a left-side position.
    fn pair(&mut self, stem: &str, region: Region, x: f64, y: f64, dz: f64) {
        self.skin(&format!("{stem}L"), region, x, y, dz);
        self.skin(&format!("{stem}R"), region, -x, y, dz);
    }
}

/// Depth of the face surface: an ellipsoid centred behind the face. Features (nose, lips) add
/// their own relief on top.
fn surface_z(x: f64, y: f64) -> f64 {
    let (a, b, c) = (78.0, 125.0, 92.0);
    let (y0, z0) = (-20.0, -80.0);
    let s = 1.0 - (x / a).powi(2) - ((y - y0) / b).powi(2);
    z0 + c * s.max(0.0).sqrt()
}

/// A Vicon-style head band: front and back markers at the temples and the back of the head,
/// named as Vicon's Plug-in Gait names them.
pub(crate) fn vicon_head_band() -> FaceGeometry {
    let mut b = Builder::default();
    let r = Region::HeadReference;
    b.at("LFHD", r, [62.0, 70.0, -45.0]);
    b.at("RFHD", r, [-62.0, 70.0, -45.0]);
    b.at("LBHD", r, [58.0, 60.0, -175.0]);
    b.at("RBHD", r, [-58.0, 60.0, -175.0]);
    FaceGeometry { markers: b.markers }
}

fn head_reference(b: &mut Builder) {
    // A rigid head band: four non-coplanar points so a rigid fit is well posed.
    let r = Region::HeadReference;
    b.at("HeadFront", r, [0.0, 85.0, -30.0]);
    b.at("HeadTop", r, [0.0, 120.0, -80.0]);
    b.at("HeadL", r, [75.0, 45.0, -60.0]);
    b.at("HeadR", r, [-75.0, 45.0, -60.0]);
}

fn upper_face(b: &mut Builder) {
    for (i, x) in [-45.0, -27.0, -9.0, 9.0, 27.0, 45.0].iter().enumerate() {
        b.skin(
            &format!("Forehead{}", i + 1),
            Region::Forehead,
            *x,
            35.0,
            0.0,
        );
    }
    for (i, x) in [-40.0, -24.0, -8.0, 8.0, 24.0, 40.0].iter().enumerate() {
        b.skin(
            &format!("Forehead{}", i + 7),
            Region::Forehead,
            *x,
            55.0,
            0.0,
        );
    }
    // Brow 1 is the inner end, 6 the outer end.
    let brow = [
        (14.0, 17.0),
        (22.0, 20.0),
        (30.0, 22.0),
        (38.0, 22.0),
        (46.0, 20.0),
        (53.0, 16.0),
    ];
    for (side, sign) in [("L", 1.0), ("R", -1.0)] {
        for (i, (x, y)) in brow.iter().enumerate() {
            let label = format!("Brow{side}{}", i + 1);
            b.skin(&label, Region::Eyebrows, sign * x, *y, 2.0);
        }
    }
    let lids = [
        ("LidUpper", 32.0, 5.0),
        ("LidUpperIn", 25.0, 4.0),
        ("LidUpperOut", 39.0, 4.0),
        ("LidLower", 32.0, -5.0),
    ];
    for (stem, x, y) in lids {
        b.pair(stem, Region::Eyelids, x, y, -2.0);
    }
}

fn nose(b: &mut Builder) {
    let r = Region::Nose;
    b.skin("NoseBridge", r, 0.0, 6.0, 6.0);
    b.skin("NoseTip", r, 0.0, -30.0, 28.0);
    b.skin("NoseBase", r, 0.0, -40.0, 15.0);
    b.pair("NoseSide", r, 9.0, -15.0, 10.0);
    b.pair("NoseAla", r, 14.0, -33.0, 10.0);
}

fn cheeks(b: &mut Builder) {
    let left: [(f64, f64); 18] = [
        (24.0, -14.0),
        (36.0, -14.0),
        (48.0, -14.0),
        (60.0, -14.0),
        (24.0, -26.0),
        (36.0, -26.0),
        (48.0, -26.0),
        (62.0, -26.0),
        (28.0, -40.0),
        (40.0, -40.0),
        (52.0, -40.0),
        (64.0, -40.0),
        (36.0, -54.0),
        (48.0, -54.0),
        (60.0, -54.0),
        (32.0, -68.0),
        (44.0, -68.0),
        (55.0, -68.0),
    ];
    for (side, sign) in [("L", 1.0), ("R", -1.0)] {
        for (i, (x, y)) in left.iter().enumerate() {
            let label = format!("Cheek{side}{}", i + 1);
            b.skin(&label, Region::Cheeks, sign * x, *y, 0.0);
        }
    }
}

/// Mouth centre height (mm).
pub(crate) const MOUTH_Y: f64 = -58.0;
/// Half-width of the mouth, corner x (mm).
pub(crate) const MOUTH_HALF_WIDTH: f64 = 25.0;

fn mouth(b: &mut Builder) {
    let r = Region::Mouth;
    b.pair("MouthCorner", r, MOUTH_HALF_WIDTH, MOUTH_Y, 2.0);
    // Lip 1 is at the subject's right (-x), 7 at the left (+x), 4 on the midline.
    for i in 0..7 {
        let x = -18.0 + 6.0 * i as f64;
        let bulge = 1.0 - (x / MOUTH_HALF_WIDTH).powi(2);
        let up = MOUTH_Y + 2.0 + 6.0 * bulge;
        b.skin(&format!("UpperLip{}", i + 1), r, x, up, 4.0 + 5.0 * bulge);
    }
    for i in 0..7 {
        let x = -18.0 + 6.0 * i as f64;
        let bulge = 1.0 - (x / MOUTH_HALF_WIDTH).powi(2);
        let down = MOUTH_Y - 2.0 - 7.0 * bulge;
        b.skin(&format!("LowerLip{}", i + 1), r, x, down, 3.0 + 4.0 * bulge);
    }
}

fn jaw(b: &mut Builder) {
    let r = Region::Jaw;
    b.skin("Mentolabial", r, 0.0, -76.0, 3.0);
    b.skin("Chin", r, 0.0, -94.0, 2.0);
    b.pair("Chin", r, 14.0, -90.0, 1.0);
    let line = [
        (26.0, -90.0),
        (40.0, -86.0),
        (53.0, -78.0),
        (63.0, -66.0),
        (69.0, -52.0),
    ];
    for (side, sign) in [("L", 1.0), ("R", -1.0)] {
        for (i, (x, y)) in line.iter().enumerate() {
            b.skin(&format!("Jaw{side}{}", i + 1), r, sign * x, *y, 0.0);
        }
    }
}

#[cfg(test)]
mod tests;
