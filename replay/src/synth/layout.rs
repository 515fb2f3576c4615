//! Face layouts other than the default: which markers the face carries, what they are called,
//! which rigid markers sit on the head, and where exactly each one is placed.
//!
//! Defaults of a model (head reference, component count, thresholds) must hold on faces the
//! generator was not built around. A [`Layout`] varies what a capture setup varies:
//!
//! | knob | values | what changes |
//! |---|---|---|
//! | [`MarkerSet`] | `full` (109 markers), `sparse` (41 face markers) | density and placement |
//! | [`Naming`] | `descriptive` (`MouthCornerL`), `snake` (`mouth_01`), `numbered` (`M001`) | whether names tell anything |
//! | [`RigidMarkers`] | `band` (4 head-band markers), `vicon` (`LFHD RFHD LBHD RBHD`), `none` | whether any marker is rigid |
//! | `placement_jitter_mm` | 0 (default) or a few mm | each marker moved at random; the face widened or narrowed by up to 8 % |
//!
//! With [`RigidMarkers::None`] the nose also moves a little with the brows, the upper lip and
//! the emotion, so that no marker of the face is rigid, as on a real face. The sources move
//! every face the same way: their fields are evaluated at each marker's place on the canonical
//! face ([`super::geometry::Marker::canonical`]).

use std::str::FromStr;

use rand::Rng;

use super::geometry::{vicon_head_band, FaceGeometry, Marker, Region};
use super::seeds::{sub_rng, Stream};

/// Which face markers a layout carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MarkerSet {
    /// The 105 face markers of the default face.
    #[default]
    Full,
    /// 41 face markers, as sparse as a typical optical face set (AnimFace, Facial-Sing).
    Sparse,
}

/// How markers are named.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Naming {
    /// Anatomical names: `MouthCornerL`, `BrowR3`, `HeadTop` (Vicon names for a Vicon band).
    #[default]
    Descriptive,
    /// Region and number, lower case: `forehead_07`, `mouth_01`, `head_02`.
    Snake,
    /// Names that tell nothing: `M001`, `M002`, ...
    Numbered,
}

/// The rigid markers on the head.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RigidMarkers {
    /// Four head-band markers (front, top, left, right).
    #[default]
    Band,
    /// A Vicon Plug-in Gait head band: `LFHD`, `RFHD`, `LBHD`, `RBHD`, two of them at the back.
    Vicon,
    /// No rigid marker at all, and a nose that moves with the face.
    None,
}

/// A face layout. See the module docs.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Layout {
    /// Face markers.
    pub markers: MarkerSet,
    /// Marker names.
    pub naming: Naming,
    /// Rigid head markers.
    pub rigid: RigidMarkers,
    /// Largest random displacement of a marker from its default place (mm); 0 keeps the
    /// default placement. Non-zero also scales the face's width and height by up to ±8 %.
    pub placement_jitter_mm: f64,
}

/// Kinds (canonical names) of the sparse marker set.
const SPARSE: [&str; 41] = [
    "Forehead3",
    "Forehead4",
    "Forehead7",
    "Forehead12",
    "BrowL1",
    "BrowL3",
    "BrowL6",
    "BrowR1",
    "BrowR3",
    "BrowR6",
    "LidUpperL",
    "LidLowerL",
    "LidUpperR",
    "LidLowerR",
    "NoseBridge",
    "NoseTip",
    "NoseAlaL",
    "NoseAlaR",
    "CheekL2",
    "CheekL6",
    "CheekL10",
    "CheekL13",
    "CheekL17",
    "CheekR2",
    "CheekR6",
    "CheekR10",
    "CheekR13",
    "CheekR17",
    "MouthCornerL",
    "MouthCornerR",
    "UpperLip2",
    "UpperLip4",
    "UpperLip6",
    "LowerLip2",
    "LowerLip4",
    "LowerLip6",
    "Mentolabial",
    "Chin",
    "ChinL",
    "ChinR",
    "JawL3",
];

/// Largest face scale change of a jittered placement (±).
const SCALE_SPREAD: f64 = 0.08;

impl Layout {
    /// True for the default layout (the 109-marker face as it always was).
    pub fn is_standard(&self) -> bool {
        *self == Layout::default()
    }

    /// Whether the nose moves with the face (no rigid marker anywhere).
    pub fn soft_nose(&self) -> bool {
        self.rigid == RigidMarkers::None
    }

    /// The face of this layout; `seed` places the markers when `placement_jitter_mm > 0`.
    pub fn face(&self, seed: u64) -> FaceGeometry {
        let standard = FaceGeometry::standard();
        let mut markers: Vec<Marker> = standard
            .markers
            .iter()
            .filter(|m| match (m.region, self.markers) {
                (Region::HeadReference, _) => self.rigid == RigidMarkers::Band,
                (_, MarkerSet::Full) => true,
                (_, MarkerSet::Sparse) => SPARSE.contains(&m.kind.as_str()),
            })
            .cloned()
            .collect();
        if self.rigid == RigidMarkers::Vicon {
            let mut band = vicon_head_band().markers;
            band.append(&mut markers);
            markers = band;
        }
        if self.placement_jitter_mm > 0.0 {
            self.jitter(&mut markers, seed);
        }
        self.rename(&mut markers);
        FaceGeometry { markers }
    }

    /// Moves every face marker by up to the jitter in x and y (z follows at a third) and scales
    /// the face; rigid markers only scale with the head.
    fn jitter(&self, markers: &mut [Marker], seed: u64) {
        let mut rng = sub_rng(seed, Stream::Layout, 0, 0);
        let sx = 1.0 + rng.random_range(-SCALE_SPREAD..SCALE_SPREAD);
        let sy = 1.0 + rng.random_range(-SCALE_SPREAD..SCALE_SPREAD);
        let j = self.placement_jitter_mm;
        for m in markers {
            let mut d = [0.0; 3];
            if m.region != Region::HeadReference {
                d = [
                    rng.random_range(-j..j),
                    rng.random_range(-j..j),
                    rng.random_range(-j..j) / 3.0,
                ];
            }
            m.rest = [
                m.rest[0] * sx + d[0],
                m.rest[1] * sy + d[1],
                m.rest[2] + d[2],
            ];
        }
    }

    fn rename(&self, markers: &mut [Marker]) {
        match self.naming {
            Naming::Descriptive => {}
            Naming::Numbered => {
                for (i, m) in markers.iter_mut().enumerate() {
                    m.label = format!("M{:03}", i + 1);
                }
            }
            Naming::Snake => {
                for region in Region::ALL {
                    let stem = match region {
                        Region::HeadReference => "head",
                        r => r.name(),
                    };
                    let in_region = markers.iter_mut().filter(|m| m.region == region);
                    for (k, m) in in_region.enumerate() {
                        m.label = format!("{stem}_{:02}", k + 1);
                    }
                }
            }
        }
    }

    /// A short description, e.g. `sparse, numbered names, no rigid markers, jitter 3 mm`.
    pub fn describe(&self) -> String {
        let markers = match self.markers {
            MarkerSet::Full => "full",
            MarkerSet::Sparse => "sparse",
        };
        let names = match self.naming {
            Naming::Descriptive => "descriptive",
            Naming::Snake => "snake",
            Naming::Numbered => "numbered",
        };
        let rigid = match self.rigid {
            RigidMarkers::Band => "head band",
            RigidMarkers::Vicon => "vicon head band",
            RigidMarkers::None => "no rigid markers",
        };
        let mut text = format!("{markers} markers, {names} names, {rigid}");
        if self.placement_jitter_mm > 0.0 {
            text.push_str(&format!(", jitter {} mm", self.placement_jitter_mm));
        }
        text
    }
}

/// A value of a layout knob that is not one of its names.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown {knob} {value:?} (expected {expected})")]
pub struct LayoutParseError {
    /// The knob.
    pub knob: &'static str,
    /// What was given.
    pub value: String,
    /// The names it accepts.
    pub expected: &'static str,
}

macro_rules! parse_names {
    ($ty:ty, $knob:literal, $expected:literal, { $($name:literal => $v:expr),+ $(,)? }) => {
        impl FromStr for $ty {
            type Err = LayoutParseError;
            fn from_str(s: &str) -> Result<$ty, LayoutParseError> {
                match s {
                    $($name => Ok($v),)+
                    _ => Err(LayoutParseError {
                        knob: $knob,
                        value: s.to_string(),
                        expected: $expected,
                    }),
                }
            }
        }
    };
}

parse_names!(MarkerSet, "marker set", "full or sparse", {
    "full" => MarkerSet::Full,
    "sparse" => MarkerSet::Sparse,
});
parse_names!(Naming, "naming", "descriptive, snake or numbered", {
    "descriptive" => Naming::Descriptive,
    "snake" => Naming::Snake,
    "numbered" => Naming::Numbered,
});
parse_names!(RigidMarkers, "rigid markers", "band, vicon or none", {
    "band" => RigidMarkers::Band,
    "vicon" => RigidMarkers::Vicon,
    "none" => RigidMarkers::None,
});

#[cfg(test)]
mod tests;
