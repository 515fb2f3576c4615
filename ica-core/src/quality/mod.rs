//! What a model knows about its own quality: how the head reference was decided and how well it
//! holds, how stable each component is, what the model leaves out, and the warnings a user must
//! read. Stored in the model file (optional: older files load without it), printed by `train`,
//! shown by `inspect` and `analyze`.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// How the head reference was decided, with the numbers behind it.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct HeadReport {
    /// Where the reference came from: `named` (the user or the regions file), `name pattern`
    /// (a common head-marker name), `geometry` (found in the capture) or `none`.
    pub source: String,
    /// The reference markers considered (the chosen ones when stabilised).
    pub markers: Vec<String>,
    /// Whether frames are stabilised on them.
    pub stabilised: bool,
    /// The decision in one line.
    pub verdict: String,
    /// The capture's noise per coordinate (mm).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise_mm: Option<f64>,
    /// Deformation of the reference markers among themselves (mm RMS per marker).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub deformation_mm: Option<f64>,
    /// Whether that deformation is within the capture's noise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rigid: Option<bool>,
    /// Head motion at the face (mm RMS).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub motion_mm: Option<f64>,
    /// Expected pose error the reference adds at the face (mm RMS).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pose_error_mm: Option<f64>,
    /// Median share of the other markers' motion the reference's pose explains (0..1): high
    /// for a part of the face, low for the head.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub leakage: Option<f64>,
    /// Stabilisation residual per reference marker over the training frames (mm RMS).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub residual_mm: BTreeMap<String, f64>,
    /// The user asked for this reference on the command line (`--head-reference`), so not
    /// using it is a warning. A regions file's `head_reference` describes the layout and asks
    /// nothing.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub requested: bool,
}

/// The kind of a [`Warning`], for tests and tools.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WarningKind {
    /// Too few frames for the number of parameters.
    FewFrames,
    /// A component is carried by one marker (a likely label swap or a glitch).
    OneMarkerComponent,
    /// The variance target keeps components at the noise floor.
    KeepsNoise,
    /// The component count leaves a large slow signal in the residual.
    SlowResidual,
    /// A component is not found again by other restarts.
    UnstableComponent,
    /// The head reference deforms, or moves with the face.
    HeadReference,
}

/// A warning about the model, with the text a user reads.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Warning {
    /// What kind of problem.
    pub kind: WarningKind,
    /// One line naming the numbers and what to do.
    pub message: String,
}

/// The model's quality report. See the module docs.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ModelQuality {
    /// The head reference decision.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub head: Option<HeadReport>,
    /// Stability of each component across restarts (component order), 0..1.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub stability: Vec<f64>,
    /// Reconstruction residual of the training frames per region (mm RMS per marker), or per
    /// marker group when no regions are known (`all`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub residual_by_region_mm: BTreeMap<String, f64>,
    /// Reconstruction residual per marker (mm RMS), model order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub residual_by_marker_mm: Vec<f64>,
    /// Largest slow signal left in the residual: the RMS at its peak marker (mm) of the
    /// strongest direction of the low-passed residual.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slow_residual_mm: Option<f64>,
    /// The marker where that slow residual peaks.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slow_residual_marker: Option<String>,
    /// Warnings, in the order found.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<Warning>,
}

impl ModelQuality {
    /// True when nothing was recorded.
    pub fn is_empty(&self) -> bool {
        *self == ModelQuality::default()
    }

    /// Adds a warning.
    pub fn warn(&mut self, kind: WarningKind, message: String) {
        self.warnings.push(Warning { kind, message });
    }

    /// Whether a warning of this kind was raised.
    pub fn has(&self, kind: WarningKind) -> bool {
        self.warnings.iter().any(|w| w.kind == kind)
    }
}
