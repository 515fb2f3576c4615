//! Preparing real captures for training: one rate, markers that are
//! mostly there, glitches removed, head motion taken out.
//!
//! 1. **Rates**: every take is resampled (linear) to the model rate, and the report says so.
//! 2. **Markers**: the first take's labels, minus markers missing in more than
//!    [`PrepOptions::max_missing_share`] of all frames (like Facial-Sing's `Unlabeled1`).
//! 3. **Glitches**: a marker moving faster than the speed limit since its last accepted sample
//!    (a swap or a spike) is treated as missing. The limit is given, or derived from the data:
//!    [`AUTO_SPEED_FACTOR`] × the 99.9th percentile of marker speeds, at least
//!    [`MIN_AUTO_SPEED_MM_S`].
//! 4. **Head**: reference markers give each frame's pose and the face is modelled in head
//!    coordinates; [`head`] decides which (named, a common head-marker name, or found in the
//!    capture) and whether the head moves enough to be worth it. The stabilisation residual is
//!    reported.
//!
//! The same [`FramePrep`] then runs in `project`, `edit` and the daemon, from the settings
//! stored in the model.

mod capture;
mod glitches;
pub mod head;
mod model;
pub mod quality;
mod streamed;

use std::ops::Range;

use anyhow::{bail, Context, Result};
use ica_core::model::CaptureSettings;
use ica_core::quality::HeadReport;
use ica_core::robust::quantile;

use capture::RefResiduals;
use glitches::glitches_per_marker;
pub use glitches::{AUTO_SPEED_FACTOR, BOUNDS_FACTOR, MIN_AUTO_SPEED_MM_S, MIN_BOUNDS_MM};
pub use head::{HeadChoice, DEFAULT_HEAD_PATTERNS};
pub use model::{train, PrepReport, Stage, TrainOptions, Trained};
pub use streamed::{train_files, StreamOptions, IN_MEMORY_FRAMES, SAMPLE_FRAMES};

use crate::offline::{self, LoadedTake, ModelFrames};
use engine::frame::FramePrep;
use engine::layout::LabelMap;

/// The glitch speed limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SpeedLimit {
    /// No glitch check.
    Off,
    /// Derived from the data.
    Auto,
    /// This many mm/s.
    MmPerS(f64),
}

/// The default share of frames a marker may miss before it is left out.
pub const DEFAULT_MAX_MISSING: f64 = 0.5;

/// Options of [`prepare`].
#[derive(Debug, Clone)]
pub struct PrepOptions {
    /// Model rate; `None` takes the first take's.
    pub rate_hz: Option<f64>,
    /// Markers missing in more than this share of frames are left out.
    pub max_missing_share: f64,
    /// Glitch speed limit.
    pub speed: SpeedLimit,
    /// Head reference.
    pub head: HeadChoice,
    /// Learn per-marker plausible regions and treat samples outside them as glitches.
    pub bounds: bool,
}

impl Default for PrepOptions {
    /// What `emoshift train` does when asked nothing.
    fn default() -> PrepOptions {
        PrepOptions {
            rate_hz: None,
            max_missing_share: DEFAULT_MAX_MISSING,
            speed: SpeedLimit::Auto,
            head: HeadChoice::Auto {
                patterns: DEFAULT_HEAD_PATTERNS
                    .iter()
                    .map(|p| p.to_string())
                    .collect(),
            },
            bounds: true,
        }
    }
}

/// Training data in model order, head coordinates, with what preparing found.
#[derive(Debug, Clone)]
pub struct PreparedData {
    /// Marker labels of the model.
    pub labels: Vec<String>,
    /// Model rate.
    pub rate_hz: f64,
    /// Frames x channels, head coordinates when stabilised.
    pub samples: Vec<f32>,
    /// Frames x channels missing flags (glitches included).
    pub missing: Vec<bool>,
    /// Settings to store in the model.
    pub capture: CaptureSettings,
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
    /// Per-frame stabilisation residual (mm), frames where the pose was estimated.
    pub residuals_mm: Vec<f64>,
    /// Reference marker labels (empty without stabilisation).
    pub reference: Vec<String>,
    /// How the head reference was decided, with its numbers (per-marker residuals filled in).
    pub head: HeadReport,
    /// Frame range of each take in `samples`.
    pub takes: Vec<Range<usize>>,
}

impl PreparedData {
    /// Median and 95th percentile of the stabilisation residual (mm).
    pub fn residual_summary(&self) -> Option<(f64, f64)> {
        residual_summary(&self.residuals_mm)
    }
}

/// Median and 95th percentile of the finite stabilisation residuals (mm).
pub(crate) fn residual_summary(residuals_mm: &[f64]) -> Option<(f64, f64)> {
    let mut r: Vec<f64> = residuals_mm
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .collect();
    if r.is_empty() {
        return None;
    }
    Some((quantile(&mut r, 0.5), quantile(&mut r, 0.95)))
}

/// Prepares loaded takes for training. See the module docs.
///
/// # Errors
/// No marker left, unknown reference labels, too few reference markers, or no take shares a
/// marker with the first.
pub fn prepare(takes: &[LoadedTake], options: &PrepOptions) -> Result<PreparedData> {
    let rate_hz = options.rate_hz.unwrap_or(takes[0].take.rate_hz);
    let names: Vec<String> = takes.iter().map(|t| t.path.display().to_string()).collect();
    let mut resampled = Vec::new();
    let takes: Vec<replay::Take> = takes
        .iter()
        .map(|t| {
            if (t.take.rate_hz - rate_hz).abs() > 1e-6 * rate_hz {
                resampled.push((t.path.display().to_string(), t.take.rate_hz, rate_hz));
                t.take.resampled(rate_hz)
            } else {
                t.take.clone()
            }
        })
        .collect();
    let KeptMarkers {
        labels,
        excluded,
        label_notes,
    } = kept_markers(&takes, &names, options.max_missing_share)?;
    let frames: Vec<ModelFrames> = takes
        .iter()
        .map(|t| {
            Ok(offline::to_model_order(
                t,
                &LabelMap::new(&labels, &t.labels)?,
            ))
        })
        .collect::<Result<_>>()?;
    let n = labels.len();
    let mut ranges = Vec::with_capacity(frames.len());
    let mut start = 0;
    for f in &frames {
        ranges.push(start..start + f.frames());
        start += f.frames();
    }
    let learned = capture::learn(&frames, &labels, &excluded, rate_hz, options)?;
    let (capture, reference, mut head_report) = (learned.capture, learned.reference, learned.head);
    let (samples, marker_missing, glitches, residuals_mm) =
        run_prep(&frames, n, rate_hz, &capture)?;
    let per_marker = glitches_per_marker(&frames, &marker_missing, n);
    if let Some(h) = &capture.head {
        let mut sums = RefResiduals::new(h);
        for (xyz, missing) in samples
            .chunks_exact(n * 3)
            .zip(marker_missing.chunks_exact(n))
        {
            sums.add_frame(xyz, missing);
        }
        head_report.residual_mm = sums.by_label(&labels);
    }
    Ok(PreparedData {
        head: head_report,
        takes: ranges,
        glitches_per_marker: per_marker,
        reference: reference.iter().map(|&i| labels[i].clone()).collect(),
        labels,
        rate_hz,
        samples,
        missing: marker_missing.iter().flat_map(|&m| [m, m, m]).collect(),
        capture,
        excluded,
        label_notes,
        resampled,
        glitches,
        residuals_mm,
    })
}

pub(crate) type PrepRun = (Vec<f32>, Vec<bool>, usize, Vec<f64>);

/// Runs every take through a fresh [`FramePrep`]: positions, per-marker mask, glitches,
/// residuals. Takes run at once on the current rayon pool, each into its own part of the
/// output, so the result does not depend on the thread count.
pub(crate) fn run_prep(
    frames: &[ModelFrames],
    n: usize,
    rate_hz: f64,
    capture: &CaptureSettings,
) -> Result<PrepRun> {
    use rayon::prelude::*;
    let total: usize = frames.iter().map(ModelFrames::frames).sum();
    let mut xyz = vec![0.0; total * n * 3];
    let mut missing = vec![false; total * n];
    let (mut xyz_rest, mut missing_rest) = (xyz.as_mut_slice(), missing.as_mut_slice());
    let mut parts = Vec::with_capacity(frames.len());
    for take in frames {
        let (x, rest) = std::mem::take(&mut xyz_rest).split_at_mut(take.frames() * n * 3);
        let (m, rest_m) = std::mem::take(&mut missing_rest).split_at_mut(take.frames() * n);
        (xyz_rest, missing_rest) = (rest, rest_m);
        parts.push((take, x, m));
    }
    let done = parts
        .into_par_iter()
        .map(|(take, x, m)| {
            let mut prep = FramePrep::new(n, rate_hz, capture);
            let (mut glitches, mut residuals) = (0, Vec::new());
            let frames = x.chunks_exact_mut(n * 3).zip(m.chunks_exact_mut(n));
            for (f, (x, m)) in frames.enumerate() {
                let (p, raw) = take.frame(f);
                let out = prep.prepare(p, raw)?;
                x.copy_from_slice(out.xyz);
                m.copy_from_slice(out.missing);
                glitches += out.info.glitches;
                if out.info.pose.is_some() && !out.info.pose_held {
                    residuals.push(out.info.residual_mm);
                }
            }
            Ok((glitches, residuals))
        })
        .collect::<Result<Vec<_>>>()?;
    let glitches = done.iter().map(|(g, _)| g).sum();
    let residuals = done.into_iter().flat_map(|(_, r)| r).collect();
    Ok((xyz, missing, glitches, residuals))
}

/// Labels kept, and the labels left out with the share of frames they were missing in.
/// The markers a model keeps, those left out, and how takes' labels differ from the first's.
#[derive(Debug, Clone)]
pub(crate) struct KeptMarkers {
    /// The first take's labels minus the markers missing too often.
    pub labels: Vec<String>,
    /// Markers left out, with the share of frames they were missing in.
    pub excluded: Vec<(String, f64)>,
    /// One line per take whose markers differ from the first take's.
    pub label_notes: Vec<String>,
}

/// The first take's labels minus the markers missing too often over all takes (`names`
/// name the takes in notes).
fn kept_markers(takes: &[replay::Take], names: &[String], max_share: f64) -> Result<KeptMarkers> {
    let mut counts = MissingCounts::new(takes[0].labels.clone());
    for (t, name) in takes.iter().zip(names) {
        counts.add(t, name).with_context(|| name.clone())?;
    }
    counts.kept(max_share)
}

/// How often each of the first take's markers is missing, over takes added one at a time.
#[derive(Debug, Clone)]
pub(crate) struct MissingCounts {
    first: Vec<String>,
    missing: Vec<usize>,
    frames: usize,
    label_notes: Vec<String>,
}

impl MissingCounts {
    pub(crate) fn new(first: Vec<String>) -> Self {
        let missing = vec![0; first.len()];
        Self {
            first,
            missing,
            frames: 0,
            label_notes: Vec::new(),
        }
    }

    /// Counts a take (at the model rate), `name` naming it in a note if its markers differ
    /// from the first take's: the first's it lacks are gaps to fill in all its frames, and
    /// its own the first does not have are left out.
    ///
    /// # Errors
    /// The take shares no marker with the first.
    pub(crate) fn add(&mut self, t: &replay::Take, name: &str) -> Result<()> {
        // The layout error speaks of a model; here there is only the first take.
        let map = LabelMap::new(&self.first, &t.labels).map_err(|_| {
            anyhow::anyhow!(
                "shares no marker with the first take (its {} markers, the first take's {})",
                t.labels.len(),
                self.first.len()
            )
        })?;
        if let Some(text) = map
            .differences(&self.first, &t.labels)
            .describe("first take")
        {
            self.label_notes.push(format!(
                "{name} {text}: those it lacks are gaps in all its frames, its others are left out"
            ));
        }
        let counts = t.missing_per_marker();
        for (i, src) in map.model_to_take.iter().enumerate() {
            self.missing[i] += match src {
                Some(j) => counts[*j],
                None => t.n_frames(),
            };
        }
        self.frames += t.n_frames();
        Ok(())
    }

    /// The markers kept and those left out (see [`PrepOptions::max_missing_share`]).
    ///
    /// # Errors
    /// Every marker is missing too often.
    pub(crate) fn kept(self, max_share: f64) -> Result<KeptMarkers> {
        let mut kept = Vec::new();
        let mut excluded = Vec::new();
        for (label, &gone) in self.first.iter().zip(&self.missing) {
            let share = gone as f64 / self.frames.max(1) as f64;
            if share > max_share {
                excluded.push((label.clone(), share));
            } else {
                kept.push(label.clone());
            }
        }
        if kept.is_empty() {
            bail!(
                "every marker is missing in more than {:.0} % of the frames",
                100.0 * max_share
            );
        }
        Ok(KeptMarkers {
            labels: kept,
            excluded,
            label_notes: self.label_notes,
        })
    }
}
