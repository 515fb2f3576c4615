//! The fitted ICA model of a face, `x ≈ mean + M·u` (paper eq. 2, `M = P·A`), and its file.
//!
//! [`IcaModel`] holds the mean, the mixing matrix `M` (channels x components), the unmixing
//! matrix `W = M⁺` (components x channels), the marker labels, the frame rate, a [`Role`] per
//! component, the named emotion levels and the [`TrainReport`]. Every constructor and the
//! loader validate, so an `IcaModel` value is always consistent: shapes agree, entries are
//! finite, `M` has full column rank and `W` is its pseudo-inverse.
//!
//! Whole takes are projected and resynthesised in f64 here ([`IcaModel::project`],
//! [`IcaModel::resynthesize`]); the per-frame f32 path is [`crate::project::Projector`].

mod check;
mod emotion;
mod error;
mod file;
mod json_rows;
mod set_emotion;
mod take;
mod target;

pub use emotion::{BlendError, Conditioning, EmotionLevels, EmotionPoint, FittedSpace};
pub use error::ModelError;
pub use file::FORMAT_VERSION;
pub use target::SpaceTarget;

use crate::quality::ModelQuality;
use crate::report::TrainReport;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

pub(crate) use check::{check_capture, check_emotion_levels, check_emotion_space};
use check::{check_finite, check_parts, check_pseudo_inverse, pseudo_inverse};

/// A mixing matrix whose smallest singular value is at most `RANK_TOL` x its largest is
/// rejected as rank deficient: beyond a condition number of 1e8 the projection amplifies f64
/// rounding to ~1e-8 of the signal and f32 rounding to more than the signal.
pub const RANK_TOL: f64 = 1e-8;

/// Largest deviation allowed in the Penrose checks of a stored unmixing matrix (`W·M = I`,
/// `M·W` symmetric). Both products are dimensionless; a model within [`RANK_TOL`] round-trips
/// through JSON at ~1e-8, so 1e-6 only trips on a matrix that was edited or corrupted.
pub const PINV_TOL: f64 = 1e-6;

/// What an independent component was found to carry (paper section 4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    /// Not analysed yet.
    #[default]
    Unknown,
    /// The emotion component.
    Emotion,
    /// Speech (mouth and jaw) motion.
    Speech,
    /// Non-emotional eyebrow motion.
    Eyebrows,
    /// Blinking.
    Eyelids,
    /// Analysed, none of the above.
    Other,
}

/// A validated ICA model. See the module docs.
#[derive(Debug, Clone, PartialEq)]
pub struct IcaModel {
    labels: Vec<String>,
    rate_hz: f64,
    mean: Vec<f64>,
    mixing: DMatrix<f64>,
    unmixing: DMatrix<f64>,
    roles: Vec<Role>,
    emotion: EmotionLevels,
    report: TrainReport,
    capture: CaptureSettings,
    quality: ModelQuality,
}

/// How frames are prepared before projection, stored so that `project`, `edit` and the daemon
/// all do exactly what training did.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct CaptureSettings {
    /// Head stabilisation: the rigid reference markers and their template. `None` models the
    /// face in capture coordinates.
    #[serde(default)]
    pub head: Option<crate::stabilise::HeadReference>,
    /// Marker speed (mm/s) above which a sample is a glitch (a swap or spike) and is treated
    /// as missing. `None` disables the check.
    #[serde(default)]
    pub max_speed_mm_s: Option<f64>,
    /// Where each marker may be, in head coordinates: a sample farther than `radius_mm` from
    /// `centre` is a glitch (a swapped or drifting label) and is treated as missing. `None`
    /// disables the check.
    #[serde(default)]
    pub bounds: Option<MarkerBounds>,
}

/// Per-marker plausible region: a ball around a centre, in the coordinates the model works in.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MarkerBounds {
    /// Centre of each marker (mm), one per model marker.
    pub centre: Vec<[f64; 3]>,
    /// Radius of each marker's ball (mm).
    pub radius_mm: Vec<f64>,
}

impl CaptureSettings {
    /// True when nothing is set (no stabilisation, no glitch check).
    pub fn is_default(&self) -> bool {
        *self == CaptureSettings::default()
    }
}

impl IcaModel {
    /// Builds a model from a fit: `x ≈ mean + mixing·u`, computing `W = mixing⁺` by SVD.
    /// Roles start [`Role::Unknown`]; there are no emotion levels yet.
    ///
    /// # Errors
    /// [`ModelError`] when shapes disagree (labels x 3 ≠ channels, mean length, report
    /// channels/components), a value is non-finite, a label is empty or repeated, the rate
    /// is not positive, or `mixing` is rank deficient (see [`RANK_TOL`]).
    pub fn new(
        labels: Vec<String>,
        rate_hz: f64,
        mean: Vec<f64>,
        mixing: DMatrix<f64>,
        report: TrainReport,
    ) -> Result<IcaModel, ModelError> {
        check_parts(&labels, rate_hz, &mean, &mixing, &report)?;
        let unmixing = pseudo_inverse(&mixing)?;
        let roles = vec![Role::Unknown; mixing.ncols()];
        Ok(IcaModel {
            labels,
            rate_hz,
            mean,
            mixing,
            unmixing,
            roles,
            emotion: EmotionLevels::default(),
            report,
            capture: CaptureSettings::default(),
            quality: ModelQuality::default(),
        })
    }

    /// Marker labels, one per marker (channels `3i..3i+3` are marker `i`'s x, y, z).
    pub fn labels(&self) -> &[String] {
        &self.labels
    }

    /// Frame rate of the training data.
    pub fn rate_hz(&self) -> f64 {
        self.rate_hz
    }

    /// The mean pose, one value per channel.
    pub fn mean(&self) -> &[f64] {
        &self.mean
    }

    /// Mixing matrix `M = P·A`, channels x components.
    pub fn mixing(&self) -> &DMatrix<f64> {
        &self.mixing
    }

    /// Unmixing matrix `W = M⁺`, components x channels.
    pub fn unmixing(&self) -> &DMatrix<f64> {
        &self.unmixing
    }

    /// Channels (markers x 3).
    pub fn channels(&self) -> usize {
        self.mixing.nrows()
    }

    /// Markers.
    pub fn markers(&self) -> usize {
        self.labels.len()
    }

    /// Independent components kept.
    pub fn components(&self) -> usize {
        self.mixing.ncols()
    }

    /// Share of the total variance the kept principal components explain (from the report).
    pub fn variance_kept(&self) -> f64 {
        self.report.variance_kept
    }

    /// The role of each component.
    pub fn roles(&self) -> &[Role] {
        &self.roles
    }

    /// The emotion component and its named levels.
    pub fn emotion(&self) -> &EmotionLevels {
        &self.emotion
    }

    /// Frame preparation (head stabilisation, glitch threshold).
    pub fn capture(&self) -> &CaptureSettings {
        &self.capture
    }

    /// Sets the frame preparation.
    ///
    /// # Errors
    /// [`ModelError::BadCapture`] for a reference marker outside the model, a template of the
    /// wrong length or not finite, or a non-positive speed limit.
    pub fn set_capture(&mut self, capture: CaptureSettings) -> Result<(), ModelError> {
        check_capture(&capture, self.markers())?;
        self.capture = capture;
        Ok(())
    }

    /// What training did.
    pub fn report(&self) -> &TrainReport {
        &self.report
    }

    /// Variance per channel (mm²) the kept components leave out: the discarded eigenvalues
    /// of the training covariance over the live channels. 0 when the report holds no
    /// eigenvalues (models assembled without training).
    pub fn residual_variance(&self) -> f64 {
        let r = &self.report;
        let live = r.channels.saturating_sub(r.dead_channels.len());
        if r.eigenvalues.len() <= r.components || live == 0 {
            return 0.0;
        }
        r.eigenvalues[r.components..].iter().sum::<f64>() / live as f64
    }

    /// The quality report (empty for models trained before it existed).
    pub fn quality(&self) -> &ModelQuality {
        &self.quality
    }

    /// Sets the quality report.
    pub fn set_quality(&mut self, quality: ModelQuality) {
        self.quality = quality;
    }

    /// Index of the marker with this label.
    pub fn marker_index(&self, label: &str) -> Option<usize> {
        self.labels.iter().position(|l| l == label)
    }

    /// Sets the role of component `k`.
    ///
    /// # Errors
    /// [`ModelError::ComponentOutOfRange`] when `k >= components`.
    pub fn set_role(&mut self, k: usize, role: Role) -> Result<(), ModelError> {
        self.check_component("role component", k)?;
        self.roles[k] = role;
        Ok(())
    }

    fn check_component(&self, what: &'static str, k: usize) -> Result<(), ModelError> {
        let components = self.components();
        if k < components {
            Ok(())
        } else {
            Err(ModelError::ComponentOutOfRange {
                what,
                index: k,
                components,
            })
        }
    }
}

#[cfg(test)]
pub(crate) mod tests;
