//! From takes to a model, as `emoshift train` and the demo run it: prepare the captures
//! ([`super::prepare`]), pick the component rule, fill the gaps for training, fit, and measure
//! the model's quality.

use anyhow::{Context, Result};
use ica_core::fit::{Components, FastIcaParams, FitData};
use ica_core::impute::{fill_gaps, GapFill};
use ica_core::measure::{noise_per_coordinate, TrainingFrames};
use ica_core::model::IcaModel;
use ica_core::whiten::DEFAULT_VARIANCE_TARGET;
use replay::session::Regions;

use super::{prepare, PrepOptions, PreparedData};
use crate::offline::LoadedTake;

/// What to train with.
#[derive(Debug, Clone)]
pub struct TrainOptions {
    /// How the captures are prepared (rate, markers, glitches, head).
    pub prep: PrepOptions,
    /// FastICA settings; the component rule is replaced when `noise_floor` is set.
    pub params: FastIcaParams,
    /// Nothing asked for the component count: the default share of the variance, stopped at
    /// the capture's noise floor ([`Components::VarianceAboveNoise`]).
    pub noise_floor: bool,
    /// Regions, for the residuals per region in the quality report.
    pub regions: Option<Regions>,
}

impl Default for TrainOptions {
    /// What `emoshift train` does when asked nothing.
    fn default() -> TrainOptions {
        TrainOptions {
            prep: PrepOptions::default(),
            params: FastIcaParams::default(),
            noise_floor: true,
            regions: None,
        }
    }
}

/// Where training is, for a progress display.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Resampling, choosing markers, glitches, the head.
    Preparing,
    /// Whitening and FastICA with this many restarts.
    Fitting {
        /// Restarts.
        restarts: usize,
    },
}

/// What preparing the captures found, for the report `train` prints (the prepared frames
/// themselves are not kept: streaming training never holds them).
#[derive(Debug, Clone)]
pub struct PrepReport {
    /// Marker labels of the model.
    pub labels: Vec<String>,
    /// Model rate.
    pub rate_hz: f64,
    /// Settings stored in the model.
    pub capture: ica_core::model::CaptureSettings,
    /// Markers left out, with the share of frames they were missing in.
    pub excluded: Vec<(String, f64)>,
    /// One line per take whose markers differ from the first take's.
    pub label_notes: Vec<String>,
    /// Takes resampled: file, from rate, to rate.
    pub resampled: Vec<(String, f64, f64)>,
    /// Samples dropped as glitches.
    pub glitches: usize,
    /// Glitches per marker (model order).
    pub glitches_per_marker: Vec<usize>,
    /// Median and 95th percentile of the stabilisation residual (mm), when stabilised.
    pub residual_summary: Option<(f64, f64)>,
    /// Reference marker labels (empty without stabilisation).
    pub reference: Vec<String>,
    /// How the head reference was decided, with its numbers.
    pub head: ica_core::quality::HeadReport,
}

impl PrepReport {
    /// The report of data prepared in memory.
    pub fn of(data: &PreparedData) -> Self {
        Self {
            labels: data.labels.clone(),
            rate_hz: data.rate_hz,
            capture: data.capture.clone(),
            excluded: data.excluded.clone(),
            label_notes: data.label_notes.clone(),
            resampled: data.resampled.clone(),
            glitches: data.glitches,
            glitches_per_marker: data.glitches_per_marker.clone(),
            residual_summary: data.residual_summary(),
            reference: data.reference.clone(),
            head: data.head.clone(),
        }
    }
}

/// A trained model and what training found on the way.
#[derive(Debug)]
pub struct Trained {
    /// The model, its frame preparation and its quality report set.
    pub model: IcaModel,
    /// What preparing the captures found.
    pub data: PrepReport,
    /// Gaps filled for training.
    pub gaps: GapFill,
    /// The capture's noise per coordinate (mm).
    pub noise_mm: f64,
    /// The default variance share was cut short at the noise floor.
    pub capped_at_noise: bool,
}

/// The component rule: the one asked for, or the default share stopped at the noise floor.
pub(super) fn component_params(options: &TrainOptions, noise_mm: f64) -> FastIcaParams {
    if options.noise_floor && noise_mm > 0.0 {
        options
            .params
            .clone()
            .components(Components::VarianceAboveNoise {
                target: DEFAULT_VARIANCE_TARGET,
                noise_var: noise_mm * noise_mm,
            })
    } else {
        options.params.clone()
    }
}

/// Whether the default variance share was cut short at the noise floor.
pub(super) fn capped_at_noise(params: &FastIcaParams, model: &IcaModel) -> bool {
    matches!(
        params.get_components(),
        Components::VarianceAboveNoise { .. }
    ) && model.variance_kept() < DEFAULT_VARIANCE_TARGET
}

/// Trains a model on `takes` held in memory. See the module docs.
///
/// # Errors
/// Preparation, gap filling or the fit refusing the data; a fitted model that fails validation.
pub fn train(
    takes: &[LoadedTake],
    options: &TrainOptions,
    progress: &mut dyn FnMut(Stage),
) -> Result<Trained> {
    progress(Stage::Preparing);
    let data = prepare(takes, &options.prep)?;
    let channels = data.labels.len() * 3;
    let noise_mm = noise_per_coordinate(&training_frames(&data));
    let params = component_params(options, noise_mm);
    // Gaps (occlusions, glitches) are filled for training, so frames with a gap still teach
    // the model; `data` keeps the real samples for the quality report.
    let mut filled = data.samples.clone();
    let (still_missing, gaps) = fill_gaps(
        &mut filled,
        &data.missing,
        channels,
        params.get_components(),
    )
    .context("training failed")?;
    let fit_data = FitData::new(&filled, channels)?.with_missing(&still_missing)?;
    progress(Stage::Fitting {
        restarts: params.get_restarts(),
    });
    let fit = params.fit(&fit_data).context("training failed")?;
    let mut model = IcaModel::new(
        data.labels.clone(),
        data.rate_hz,
        fit.mean,
        fit.mixing,
        fit.report,
    )
    .context("the fitted model failed validation")?;
    model.set_capture(data.capture.clone())?;
    model.set_quality(super::quality::assess(
        &model,
        &data,
        options.regions.as_ref(),
    ));
    let capped_at_noise = capped_at_noise(&params, &model);
    Ok(Trained {
        model,
        data: PrepReport::of(&data),
        gaps,
        noise_mm,
        capped_at_noise,
    })
}

/// The prepared data as the quality measures read it.
pub(crate) fn training_frames(data: &PreparedData) -> TrainingFrames<'_> {
    TrainingFrames {
        samples: &data.samples,
        missing: &data.missing,
        channels: data.labels.len() * 3,
        takes: &data.takes,
        rate_hz: data.rate_hz,
    }
}
