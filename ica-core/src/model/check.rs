//! Validation of a model's parts: every constructor and the loader go through these, so an
//! [`IcaModel`](super::IcaModel) value is always consistent.

use std::collections::{BTreeMap, HashMap};

use nalgebra::DMatrix;

use super::{CaptureSettings, EmotionLevels, EmotionPoint, ModelError, PINV_TOL, RANK_TOL};
use crate::report::TrainReport;

/// Checks an emotion space against a model of `m` components: components in range, ascending
/// and unique; every point finite with one level (and one spread, if any) per component.
pub(crate) fn check_emotion_space(
    components: &[usize],
    points: &BTreeMap<String, EmotionPoint>,
    m: usize,
) -> Result<(), ModelError> {
    for (i, &k) in components.iter().enumerate() {
        if k >= m || (i > 0 && components[i - 1] >= k) {
            return Err(ModelError::ComponentOutOfRange {
                what: "emotion component",
                index: k,
                components: m,
            });
        }
    }
    for (name, p) in points {
        let spread_ok = p.spread.is_empty() || p.spread.len() == components.len();
        let finite = p.level.iter().chain(&p.spread).all(|v| v.is_finite());
        if p.level.len() != components.len() || !spread_ok || !finite {
            return Err(ModelError::NonFiniteLevel { name: name.clone() });
        }
    }
    Ok(())
}

/// Checks a whole emotion space against a model of `m` components: the components as
/// [`check_emotion_space`] does when the space has no fitted axes; with axes, every axis and
/// move a finite row of `m` values, as many moves as axes, and every point, spread and
/// persistence one finite value per axis.
pub(crate) fn check_emotion_levels(e: &EmotionLevels, m: usize) -> Result<(), ModelError> {
    if e.axes.is_empty() && e.moves.is_empty() {
        check_emotion_space(&e.components, &e.points, m)?;
    } else {
        check_emotion_space(&e.components, &BTreeMap::new(), m)?;
        let bad = |name: &str| ModelError::NonFiniteLevel {
            name: name.to_string(),
        };
        let rows_ok = |rows: &[Vec<f64>]| {
            rows.len() == e.axes.len()
                && rows
                    .iter()
                    .all(|r| r.len() == m && r.iter().all(|v| v.is_finite()))
        };
        if !rows_ok(&e.axes) {
            return Err(bad("emotion axes"));
        }
        if !rows_ok(&e.moves) {
            return Err(bad("emotion moves"));
        }
        let d = e.axes.len();
        for (name, p) in &e.points {
            let spread_ok = p.spread.is_empty() || p.spread.len() == d;
            let finite = p.level.iter().chain(&p.spread).all(|v| v.is_finite());
            if p.level.len() != d || !spread_ok || !finite {
                return Err(bad(name));
            }
        }
    }
    let d = e.dims();
    let persistence_ok = e.persistence.is_empty() || e.persistence.len() == d;
    if !persistence_ok || e.persistence.iter().any(|v| !v.is_finite()) {
        return Err(ModelError::NonFiniteLevel {
            name: "persistence".into(),
        });
    }
    if let Some(index) = e.component.filter(|&k| k >= m) {
        return Err(ModelError::ComponentOutOfRange {
            what: "emotion component",
            index,
            components: m,
        });
    }
    Ok(())
}

/// Validates everything about a model's parts except the unmixing matrix.
pub(crate) fn check_parts(
    labels: &[String],
    rate_hz: f64,
    mean: &[f64],
    mixing: &DMatrix<f64>,
    report: &TrainReport,
) -> Result<(), ModelError> {
    let (n, m) = mixing.shape();
    if n % 3 != 0 {
        return Err(ModelError::ChannelsNotTriples { channels: n });
    }
    if m == 0 || m > n {
        return Err(ModelError::ComponentCount {
            components: m,
            channels: n,
        });
    }
    if labels.len() * 3 != n {
        return Err(ModelError::LabelCount {
            channels: n,
            expected: n / 3,
            got: labels.len(),
        });
    }
    check_labels(labels)?;
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        return Err(ModelError::InvalidRate { rate_hz });
    }
    if mean.len() != n {
        return Err(ModelError::ShapeMismatch {
            what: "mean",
            expected: (n, 1),
            got: (mean.len(), 1),
        });
    }
    if let Some(row) = mean.iter().position(|v| !v.is_finite()) {
        return Err(ModelError::NonFinite {
            what: "mean",
            row,
            col: 0,
        });
    }
    check_finite("mixing", mixing)?;
    if report.channels != n {
        return Err(ModelError::ReportMismatch {
            what: "channels",
            expected: n,
            got: report.channels,
        });
    }
    if report.components != m {
        return Err(ModelError::ReportMismatch {
            what: "components",
            expected: m,
            got: report.components,
        });
    }
    Ok(())
}

fn check_labels(labels: &[String]) -> Result<(), ModelError> {
    let mut seen: HashMap<&str, usize> = HashMap::with_capacity(labels.len());
    for (index, label) in labels.iter().enumerate() {
        if label.is_empty() {
            return Err(ModelError::EmptyLabel { index });
        }
        if let Some(&first) = seen.get(label.as_str()) {
            return Err(ModelError::DuplicateLabel {
                label: label.clone(),
                first,
                second: index,
            });
        }
        seen.insert(label, index);
    }
    Ok(())
}

pub(crate) fn check_finite(what: &'static str, matrix: &DMatrix<f64>) -> Result<(), ModelError> {
    for (col, column) in matrix.column_iter().enumerate() {
        if let Some(row) = column.iter().position(|v| !v.is_finite()) {
            return Err(ModelError::NonFinite { what, row, col });
        }
    }
    Ok(())
}

/// `M⁺` by SVD, refusing a rank-deficient `M` instead of silently truncating it: a dropped
/// direction would make `W·M ≠ I` and edits of that component would vanish.
pub(crate) fn pseudo_inverse(mixing: &DMatrix<f64>) -> Result<DMatrix<f64>, ModelError> {
    let svd = mixing.clone().svd(true, true);
    let largest = svd.singular_values.iter().copied().fold(0.0_f64, f64::max);
    let smallest = svd
        .singular_values
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    if smallest.is_nan() || smallest <= RANK_TOL * largest {
        return Err(ModelError::RankDeficient {
            smallest,
            largest,
            tol: RANK_TOL,
        });
    }
    svd.pseudo_inverse(0.5 * smallest)
        .map_err(|_| ModelError::RankDeficient {
            smallest,
            largest,
            tol: RANK_TOL,
        })
}

/// The two Penrose conditions that, given full column rank, pin `W` to `M⁺`: `W·M = I` (a
/// left inverse) and `M·W` symmetric (the orthogonal projector, so off-model noise is
/// projected orthogonally, not along some other left inverse's direction).
pub(crate) fn check_pseudo_inverse(
    mixing: &DMatrix<f64>,
    unmixing: &DMatrix<f64>,
) -> Result<(), ModelError> {
    let m = mixing.ncols();
    let wm = unmixing * mixing;
    let left = (wm - DMatrix::<f64>::identity(m, m)).amax();
    if left.is_nan() || left > PINV_TOL {
        return Err(ModelError::NotPseudoInverse {
            check: "W·M = I",
            residual: left,
            tol: PINV_TOL,
        });
    }
    let mw = mixing * unmixing;
    let asym = (&mw - mw.transpose()).amax();
    if asym.is_nan() || asym > PINV_TOL {
        return Err(ModelError::NotPseudoInverse {
            check: "M·W symmetric",
            residual: asym,
            tol: PINV_TOL,
        });
    }
    Ok(())
}

/// Checks stored frame-preparation settings against the marker count.
pub(crate) fn check_capture(capture: &CaptureSettings, markers: usize) -> Result<(), ModelError> {
    let bad = |problem: String| Err(ModelError::BadCapture { problem });
    if let Some(head) = &capture.head {
        if let Some(&index) = head.markers.iter().find(|&&i| i >= markers) {
            return bad(format!(
                "head reference marker {index} is outside the {markers} markers"
            ));
        }
        if head.markers.len() < 3 || head.template.len() != head.markers.len() {
            return bad(format!(
                "head reference needs 3 or more markers with one template point each, got {} markers and {} points",
                head.markers.len(),
                head.template.len()
            ));
        }
        if head.template.iter().flatten().any(|v| !v.is_finite()) {
            return bad("head reference template is not finite".into());
        }
    }
    if let Some(b) = &capture.bounds {
        if b.centre.len() != markers || b.radius_mm.len() != markers {
            return bad(format!(
                "marker bounds hold {} centres and {} radii for {markers} markers",
                b.centre.len(),
                b.radius_mm.len()
            ));
        }
        let finite = b.centre.iter().flatten().all(|v| v.is_finite());
        if !finite || b.radius_mm.iter().any(|r| !(r.is_finite() && *r > 0.0)) {
            return bad("marker bounds must be finite with positive radii".into());
        }
    }
    if let Some(v) = capture.max_speed_mm_s {
        if !(v.is_finite() && v > 0.0) {
            return bad(format!("max_speed_mm_s must be positive, got {v}"));
        }
    }
    Ok(())
}
