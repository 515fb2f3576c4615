//! The end of a streamed training: the head report and quality measures of the session, the
//! fitted model with its quality report, and what the preparation found.

use std::collections::BTreeMap;

use anyhow::{Context, Result};
use ica_core::model::IcaModel;

use super::collect::Collected;
use super::{capture, scan};
use crate::offline::training::quality::{self, Measures};
use crate::offline::training::{residual_summary, PrepReport, TrainOptions};

/// The head report with the residuals measured over the session, and the quality measures.
pub(super) fn measured(
    learned: &capture::Learned,
    head_residuals: Option<BTreeMap<String, f64>>,
    (residual_by_marker_mm, slow_residual): (Vec<f64>, Option<(f64, usize)>),
    noise_mm: f64,
) -> (ica_core::quality::HeadReport, Measures) {
    let mut head = learned.head.clone();
    if let Some(residuals) = head_residuals {
        head.residual_mm = residuals;
    }
    let measures = Measures {
        residual_by_marker_mm,
        slow_residual,
        noise_mm,
    };
    (head, measures)
}

/// The fitted model, with its capture settings and quality report.
pub(super) fn fitted_model(
    scanned: &scan::Scan,
    learned: &capture::Learned,
    fit: ica_core::fit::FitOutput,
    (head, measures): (&ica_core::quality::HeadReport, Measures),
    options: &TrainOptions,
) -> Result<IcaModel> {
    let mut model = IcaModel::new(
        scanned.labels.clone(),
        scanned.rate_hz,
        fit.mean,
        fit.mixing,
        fit.report,
    )
    .context("the fitted model failed validation")?;
    model.set_capture(learned.capture.clone())?;
    model.set_quality(quality::assess_measured(
        &model,
        head,
        measures,
        options.regions.as_ref(),
    ));
    Ok(model)
}

/// What the streamed preparation found, for the report.
pub(super) fn prep_report(
    scanned: scan::Scan,
    learned: capture::Learned,
    collected: &Collected,
    model: &IcaModel,
    head: ica_core::quality::HeadReport,
) -> PrepReport {
    PrepReport {
        labels: scanned.labels,
        rate_hz: scanned.rate_hz,
        capture: learned.capture,
        excluded: scanned.excluded,
        label_notes: scanned.label_notes,
        resampled: scanned.resampled,
        glitches: collected.glitches,
        glitches_per_marker: collected.glitches_per_marker.clone(),
        residual_summary: residual_summary(&collected.residuals.values),
        reference: learned
            .reference
            .iter()
            .map(|&i| model.labels()[i].clone())
            .collect(),
        head,
    }
}
