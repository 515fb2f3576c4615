//! Edits in component space (paper section 5), per frame and on whole takes.
//!
//! - *Translate*: `u + α e_k`, an offset on one component ([`FrameEdit::set_offset`],
//!   [`translate`]).
//! - Gain: `u_k ← g_k u_k` ([`FrameEdit::set_gain`], [`scale_component`]).
//! - *Copy and Replace*: component `k` of take 1 replaced by that of take 2
//!   ([`set_component_from`], or per frame [`FrameEdit::set_override`]).
//! - *Copy and Add* across two models: `x = mean₁ + M₁u₁ + M₂ (u₂ᵀe_k) e_k`
//!   ([`copy_add_into`] per frame).
//!
//! Whole takes are component series, frames x components (`DMatrix<f64>`, as
//! [`crate::model::IcaModel::project`] returns them). Takes of different lengths must be
//! aligned (resampled or time-warped) by the caller before a replace.

pub use crate::frame::{EditError, FrameEdit};

use crate::frame::FrameError;
use crate::project::Projector;
use nalgebra::DMatrix;

/// *Copy and Add* for one frame: `out = mean₁ + M₁u₁ + M₂[:, k] · u₂[k]`, adding component
/// `k` of a second model's frame to the first model's resynthesis. Both models must have the
/// same channels (the same markers in the same order).
///
/// # Errors
/// [`FrameError`] when a buffer does not match its model or `k` is out of range.
pub fn copy_add_into(
    target: &Projector,
    u1: &[f32],
    source: &Projector,
    u2: &[f32],
    k: usize,
    out: &mut [f32],
) -> Result<(), FrameError> {
    if source.channels() != target.channels() {
        return Err(FrameError::Length {
            what: "source model channels",
            expected: target.channels(),
            got: source.channels(),
        });
    }
    let value = *u2.get(k).ok_or(FrameError::ComponentOutOfRange {
        index: k,
        components: u2.len(),
    })?;
    target.resynth_into(u1, out)?;
    source.add_component_into(k, value, out)
}

/// *Translate* a whole take: `u_k += alpha` in every frame.
///
/// # Errors
/// [`EditError`] for a bad index or a non-finite `alpha`.
pub fn translate(series: &mut DMatrix<f64>, k: usize, alpha: f64) -> Result<(), EditError> {
    check_series(series, k, "offset", alpha)?;
    series.column_mut(k).add_scalar_mut(alpha);
    Ok(())
}

/// Scale component `k` of a whole take by `gain`.
///
/// # Errors
/// [`EditError`] for a bad index or a non-finite `gain`.
pub fn scale_component(series: &mut DMatrix<f64>, k: usize, gain: f64) -> Result<(), EditError> {
    check_series(series, k, "gain", gain)?;
    series.column_mut(k).scale_mut(gain);
    Ok(())
}

/// Replace component `k` of a whole take with `values`, one per frame: the basis of *Copy
/// and Replace* (`values` being component `k` of another take, aligned to this one).
///
/// # Errors
/// [`EditError::SeriesLength`] when `values` has not one value per frame; bad index or a
/// non-finite value as for the other edits.
pub fn set_component_from(
    series: &mut DMatrix<f64>,
    k: usize,
    values: &[f64],
) -> Result<(), EditError> {
    check_series(series, k, "value", 0.0)?;
    if values.len() != series.nrows() {
        return Err(EditError::SeriesLength {
            expected: series.nrows(),
            got: values.len(),
        });
    }
    if let Some(&value) = values.iter().find(|v| !v.is_finite()) {
        return Err(EditError::NonFinite {
            what: "value",
            index: k,
            value,
        });
    }
    series.column_mut(k).copy_from_slice(values);
    Ok(())
}

/// *Copy and Replace* between two aligned takes of the same model: component `k` of
/// `target` becomes component `k` of `source`.
///
/// # Errors
/// As [`set_component_from`].
pub fn copy_replace(
    target: &mut DMatrix<f64>,
    source: &DMatrix<f64>,
    k: usize,
) -> Result<(), EditError> {
    if k >= source.ncols() {
        return Err(EditError::ComponentOutOfRange {
            index: k,
            components: source.ncols(),
        });
    }
    let values: Vec<f64> = source.column(k).iter().copied().collect();
    set_component_from(target, k, &values)
}

fn check_series(
    series: &DMatrix<f64>,
    k: usize,
    what: &'static str,
    value: f64,
) -> Result<(), EditError> {
    if k >= series.ncols() {
        return Err(EditError::ComponentOutOfRange {
            index: k,
            components: series.ncols(),
        });
    }
    if !value.is_finite() {
        return Err(EditError::NonFinite {
            what,
            index: k,
            value,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests;
