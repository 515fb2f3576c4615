//! The model file: JSON, matrices as arrays of rows, one row per line.
//!
//! Layout (version 1), in this order: `format_version`, `labels`, `rate_hz`, `mean`
//! (channels), `mixing` (channels rows of components), `unmixing` (components rows of
//! channels), `roles`, `emotion` (`component`, `levels`), `report`, and the optional `capture`
//! (frame preparation) and `quality` (the model's own quality report).
//!
//! Compatibility policy:
//! - Fields added later are optional with `#[serde(default)]` (as `roles` and `emotion` are
//!   already: a file without them loads with unknown roles and no levels), so files written
//!   by older builds keep loading without a version bump. Head-stabilisation settings, for
//!   example, would arrive as an optional `head` field.
//! - Unknown fields are ignored, so an older build can read a newer file that only added
//!   optional fields. A change that alters the meaning of existing fields bumps
//!   [`FORMAT_VERSION`]; the loader checks the version before anything else.
//!
//! `W` is stored, not recomputed, so that other tools can read it and every build projects
//! with exactly the matrix that was saved. The loader verifies it against `M` (see
//! [`super::PINV_TOL`]) rather than trusting it.

use super::json_rows::RowsFormatter;
use super::{
    check_finite, check_parts, check_pseudo_inverse, CaptureSettings, EmotionLevels, IcaModel,
    ModelError, Role,
};
use crate::quality::ModelQuality;
use crate::report::TrainReport;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};
use std::io::{Read, Write};

/// Version of the model file layout this build reads and writes.
pub const FORMAT_VERSION: u32 = 1;

#[derive(Serialize, Deserialize)]
struct ModelFile {
    format_version: u32,
    labels: Vec<String>,
    rate_hz: f64,
    mean: Vec<f64>,
    mixing: Vec<Vec<f64>>,
    unmixing: Vec<Vec<f64>>,
    #[serde(default)]
    roles: Vec<Role>,
    #[serde(default)]
    emotion: EmotionLevels,
    report: TrainReport,
    // Omitted when default, so models without head stabilisation keep their version-1 bytes.
    #[serde(default, skip_serializing_if = "CaptureSettings::is_default")]
    capture: CaptureSettings,
    // Optional: files written before the quality report load with an empty one.
    #[serde(default, skip_serializing_if = "ModelQuality::is_empty")]
    quality: ModelQuality,
}

/// Only the version, read first so that a future layout fails with
/// [`ModelError::UnsupportedVersion`] instead of a confusing field error.
#[derive(Deserialize)]
struct VersionProbe {
    format_version: Option<serde_json::Value>,
}

impl IcaModel {
    /// Writes the model as JSON (see the layout in this module's source docs).
    ///
    /// # Errors
    /// [`ModelError::Write`] when the writer fails.
    pub fn save(&self, writer: impl Write) -> Result<(), ModelError> {
        let file = ModelFile {
            format_version: FORMAT_VERSION,
            labels: self.labels.clone(),
            rate_hz: self.rate_hz,
            mean: self.mean.clone(),
            mixing: to_rows(&self.mixing),
            unmixing: to_rows(&self.unmixing),
            roles: self.roles.clone(),
            emotion: self.emotion.clone(),
            report: self.report.clone(),
            capture: self.capture.clone(),
            quality: self.quality.clone(),
        };
        let mut ser = serde_json::Serializer::with_formatter(writer, RowsFormatter::default());
        file.serialize(&mut ser).map_err(ModelError::Write)?;
        let mut writer = ser.into_inner();
        writer
            .write_all(b"\n")
            .map_err(|e| ModelError::Write(serde_json::Error::io(e)))
    }

    /// Reads and validates a model written by [`IcaModel::save`].
    ///
    /// # Errors
    /// [`ModelError::Read`] on I/O failure; [`ModelError::Malformed`] (with line and column)
    /// for invalid JSON or a field of the wrong type; [`ModelError::MissingVersion`] /
    /// [`ModelError::UnsupportedVersion`]; then every check of [`IcaModel::new`], plus
    /// [`ModelError::NotPseudoInverse`] for a stored `W` that is not `M⁺`, and
    /// [`ModelError::ComponentOutOfRange`] for a bad emotion component.
    pub fn load(mut reader: impl Read) -> Result<IcaModel, ModelError> {
        let mut text = String::new();
        reader.read_to_string(&mut text).map_err(ModelError::Read)?;
        let probe: VersionProbe = serde_json::from_str(&text).map_err(malformed)?;
        match probe.format_version {
            None => return Err(ModelError::MissingVersion),
            Some(v) if v.as_u64() == Some(u64::from(FORMAT_VERSION)) => {}
            Some(v) => {
                return Err(ModelError::UnsupportedVersion {
                    // A non-integer version reads as u64::MAX: unsupported either way.
                    found: v.as_u64().unwrap_or(u64::MAX),
                    supported: FORMAT_VERSION,
                });
            }
        }
        let file: ModelFile = serde_json::from_str(&text).map_err(malformed)?;
        from_file(file)
    }
}

fn from_file(file: ModelFile) -> Result<IcaModel, ModelError> {
    let mixing = from_rows("mixing", &file.mixing, 0)?;
    let (n, m) = mixing.shape();
    check_parts(
        &file.labels,
        file.rate_hz,
        &file.mean,
        &mixing,
        &file.report,
    )?;
    let unmixing = from_rows("unmixing", &file.unmixing, n)?;
    if unmixing.shape() != (m, n) {
        return Err(ModelError::ShapeMismatch {
            what: "unmixing",
            expected: (m, n),
            got: unmixing.shape(),
        });
    }
    check_finite("unmixing", &unmixing)?;
    check_pseudo_inverse(&mixing, &unmixing)?;
    let roles = if file.roles.is_empty() {
        vec![Role::Unknown; m]
    } else {
        file.roles
    };
    if roles.len() != m {
        return Err(ModelError::ShapeMismatch {
            what: "roles",
            expected: (m, 1),
            got: (roles.len(), 1),
        });
    }
    super::check_emotion_levels(&file.emotion, m)?;
    if let Some(name) = file
        .emotion
        .levels
        .iter()
        .find(|(_, v)| !v.is_finite())
        .map(|(k, _)| k)
    {
        return Err(ModelError::NonFiniteLevel { name: name.clone() });
    }
    super::check_capture(&file.capture, file.labels.len())?;
    Ok(IcaModel {
        labels: file.labels,
        rate_hz: file.rate_hz,
        mean: file.mean,
        mixing,
        unmixing,
        roles,
        emotion: file.emotion,
        report: file.report,
        capture: file.capture,
        quality: file.quality,
    })
}

fn malformed(source: serde_json::Error) -> ModelError {
    ModelError::Malformed {
        line: source.line(),
        column: source.column(),
        source,
    }
}

fn to_rows(matrix: &DMatrix<f64>) -> Vec<Vec<f64>> {
    matrix
        .row_iter()
        .map(|row| row.iter().copied().collect())
        .collect()
}

/// Rows to a matrix. An empty list of rows becomes `0 x empty_cols` so the shape check that
/// follows reports it against the expected shape.
fn from_rows(
    what: &'static str,
    rows: &[Vec<f64>],
    empty_cols: usize,
) -> Result<DMatrix<f64>, ModelError> {
    let cols = rows.first().map_or(empty_cols, Vec::len);
    if let Some((row, r)) = rows.iter().enumerate().find(|(_, r)| r.len() != cols) {
        return Err(ModelError::RaggedRow {
            what,
            row,
            expected: cols,
            got: r.len(),
        });
    }
    Ok(DMatrix::from_fn(rows.len(), cols, |i, j| rows[i][j]))
}
