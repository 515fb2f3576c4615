//! The quality report of a freshly trained model: the head decision, component stability,
//! residuals per region, the slow residual, and the warnings they raise.

use std::collections::BTreeMap;

use ica_core::measure::{
    noise_per_coordinate, one_marker_components, residual_by_marker, slow_residual, TrainingFrames,
};
use ica_core::model::IcaModel;
use ica_core::quality::{HeadReport, ModelQuality, WarningKind};
use ica_core::stabilise::search::FACE_LEAKAGE;
use replay::session::Regions;

use super::PreparedData;

/// A component that other restarts find with a best-match |correlation| below this is unstable.
pub const UNSTABLE_BELOW: f64 = 0.9;
/// Fewer used frames than this many per channel: the covariance is poorly estimated.
pub const FRAMES_PER_CHANNEL: usize = 5;
/// A component putting this share of its motion on one marker is carried by that marker.
pub const ONE_MARKER_SHARE: f64 = 0.8;
/// A kept component whose variance is below this many times the noise variance per
/// coordinate models noise.
pub const NOISE_EIGEN_FACTOR: f64 = 2.0;
/// A slow residual above this (mm RMS at its peak marker) is a signal the model cannot hold.
pub const SLOW_RESIDUAL_MM: f64 = 1.0;

/// The measures behind the report, taken on the training frames.
#[derive(Debug, Clone)]
pub struct Measures {
    /// Reconstruction residual per marker (mm RMS).
    pub residual_by_marker_mm: Vec<f64>,
    /// The slow residual (mm RMS at its peak marker) and the marker.
    pub slow_residual: Option<(f64, usize)>,
    /// The capture's noise per coordinate (mm).
    pub noise_mm: f64,
}

/// Measures the quality of `model`, trained on `data`; `regions` groups the residuals.
pub fn assess(model: &IcaModel, data: &PreparedData, regions: Option<&Regions>) -> ModelQuality {
    let frames = TrainingFrames {
        samples: &data.samples,
        missing: &data.missing,
        channels: data.labels.len() * 3,
        takes: &data.takes,
        rate_hz: data.rate_hz,
    };
    let measures = Measures {
        residual_by_marker_mm: residual_by_marker(model, &frames),
        slow_residual: slow_residual(model, &frames),
        noise_mm: noise_per_coordinate(&frames),
    };
    assess_measured(model, &data.head, measures, regions)
}

/// The quality report from measures taken already (streaming training takes them while it
/// reads the frames).
pub fn assess_measured(
    model: &IcaModel,
    head: &HeadReport,
    measures: Measures,
    regions: Option<&Regions>,
) -> ModelQuality {
    let mut q = ModelQuality {
        head: Some(head.clone()),
        stability: model.report().stability.clone(),
        residual_by_marker_mm: measures.residual_by_marker_mm,
        ..ModelQuality::default()
    };
    q.residual_by_region_mm = by_region(&q.residual_by_marker_mm, model.labels(), regions);
    if let Some((mm, marker)) = measures.slow_residual {
        q.slow_residual_mm = Some(mm);
        q.slow_residual_marker = Some(model.labels()[marker].clone());
    }
    warn_head(&mut q);
    warn_frames(&mut q, model);
    warn_components(&mut q, model);
    warn_noise(&mut q, model, measures.noise_mm);
    if let (Some(mm), Some(marker)) = (q.slow_residual_mm, q.slow_residual_marker.clone()) {
        if mm > SLOW_RESIDUAL_MM {
            q.warn(
                WarningKind::SlowResidual,
                format!(
                    "the model leaves out a slow signal of {mm:.2} mm RMS (peak at {marker}): {} components cannot hold it; raise --components or --variance, or check {marker} for a slow drift (a loose marker) with emoshift info",
                    model.components()
                ),
            );
        }
    }
    q
}

/// RMS over the markers of each region (or `all`, with no regions).
fn by_region(
    per_marker: &[f64],
    labels: &[String],
    regions: Option<&Regions>,
) -> BTreeMap<String, f64> {
    let rms = |idx: &[usize]| {
        let sq: f64 = idx.iter().map(|&i| per_marker[i].powi(2)).sum();
        (sq / idx.len().max(1) as f64).sqrt()
    };
    let mut out = BTreeMap::new();
    out.insert(
        "all".to_string(),
        rms(&(0..labels.len()).collect::<Vec<_>>()),
    );
    // Regions that name markers this model does not have are skipped, not an error: the
    // report is about what the model holds.
    for (name, patterns) in regions.map(|r| r.regions.iter()).into_iter().flatten() {
        let one = Regions {
            regions: [(name.clone(), patterns.clone())].into(),
        };
        if let Ok(mut resolved) = one.resolve(labels) {
            if let Some(idx) = resolved.remove(name) {
                out.insert(name.clone(), rms(&idx));
            }
        }
    }
    out
}

fn warn_head(q: &mut ModelQuality) {
    let Some(h) = q.head.clone() else {
        return;
    };
    if h.requested && !h.stabilised {
        let why = h
            .verdict
            .strip_prefix("not stabilised: ")
            .unwrap_or(&h.verdict);
        q.warn(
            WarningKind::HeadReference,
            format!(
                "the head reference named by --head-reference ({}) is not used, and frames are not stabilised: {why}; name markers that move with the head only (forehead, temples, a headband), or train without one (--head-reference none)",
                h.markers.join(", ")
            ),
        );
    }
    if h.stabilised && h.rigid == Some(false) {
        q.warn(
            WarningKind::HeadReference,
            format!(
                "the head reference ({}) deforms by {:.2} mm RMS, beyond the capture's noise ({:.3} mm): expect about {:.2} mm of pose error on every marker; name stiffer markers with --head-reference (forehead, temples, a headband), or train without one (--head-reference none)",
                h.markers.join(", "),
                h.deformation_mm.unwrap_or(f64::NAN),
                h.noise_mm.unwrap_or(f64::NAN),
                h.pose_error_mm.unwrap_or(f64::NAN)
            ),
        );
    }
    if h.stabilised && h.leakage.is_some_and(|l| l >= FACE_LEAKAGE) {
        q.warn(
            WarningKind::HeadReference,
            format!(
                "the head reference ({}) moves with the face: its pose explains {:.0} % of the other markers' motion; name markers away from the brows, eyes and mouth with --head-reference, or train without one (--head-reference none)",
                h.markers.join(", "),
                100.0 * h.leakage.unwrap_or(0.0)
            ),
        );
    }
}

fn warn_frames(q: &mut ModelQuality, model: &IcaModel) {
    let r = model.report();
    let needed = FRAMES_PER_CHANNEL * r.channels;
    if r.frames_used < needed {
        q.warn(
            WarningKind::FewFrames,
            format!(
                "trained on {} frames for {} channels and {} components: the covariance needs at least {needed} frames ({FRAMES_PER_CHANNEL} per channel); the model fits these frames, not the face; record more takes or longer ones, or leave markers out",
                r.frames_used, r.channels, r.components
            ),
        );
    }
}

fn warn_components(q: &mut ModelQuality, model: &IcaModel) {
    for (i, marker, share) in one_marker_components(model, ONE_MARKER_SHARE) {
        q.warn(
            WarningKind::OneMarkerComponent,
            format!(
                "component {i} is carried by marker {} alone ({:.0} % of its motion): a likely label swap or glitch; look at that marker with emoshift info and fix the takes with emoshift repair, or leave it out of the takes",
                model.labels()[marker],
                100.0 * share
            ),
        );
    }
    let unstable: Vec<String> = q
        .stability
        .iter()
        .enumerate()
        .filter(|(_, &s)| s < UNSTABLE_BELOW)
        // Rounded down, so a value just under the bound never reads as the bound.
        .map(|(i, s)| format!("c{i} ({:.2})", (s * 100.0).floor() / 100.0))
        .collect();
    if !unstable.is_empty() {
        q.warn(
            WarningKind::UnstableComponent,
            format!(
                "components not found again by the other restarts (best-match |corr| below {UNSTABLE_BELOW}): {}; try fewer components (--components {}), more frames (more or longer takes), or more restarts (--restarts {})",
                unstable.join(", "),
                model.components().saturating_sub(unstable.len()).max(1),
                2 * model.report().restarts.len().max(1)
            ),
        );
    }
}

fn warn_noise(q: &mut ModelQuality, model: &IcaModel, noise_mm: f64) {
    let r = model.report();
    let floor = NOISE_EIGEN_FACTOR * noise_mm * noise_mm;
    let kept = &r.eigenvalues[..r.components.min(r.eigenvalues.len())];
    let at_floor = kept.iter().filter(|&&e| e <= floor).count();
    if at_floor > 0 {
        let mostly = if 2 * at_floor > kept.len() {
            "mostly noise"
        } else {
            "some noise"
        };
        q.warn(
            WarningKind::KeepsNoise,
            format!(
                "{at_floor} of {} kept components are at the noise floor (variance at most {NOISE_EIGEN_FACTOR} x {noise_mm:.3}² mm²): the model keeps {mostly}; lower --variance or --components",
                kept.len()
            ),
        );
    }
}
