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

mod glitches;
pub mod head;
mod model;
pub mod quality;

use std::ops::Range;

use anyhow::{bail, Result};
use ica_core::model::CaptureSettings;
use ica_core::quality::HeadReport;
use ica_core::robust::quantile;
use ica_core::stabilise::{MarkerFrames, Stabiliser};

use glitches::{auto_speed, glitches_per_marker, marker_bounds};
pub use glitches::{AUTO_SPEED_FACTOR, BOUNDS_FACTOR, MIN_AUTO_SPEED_MM_S, MIN_BOUNDS_MM};
pub use head::{HeadChoice, DEFAULT_HEAD_PATTERNS};
pub use model::{train, Stage, TrainOptions, Trained};

use crate::engine::frame::FramePrep;
use crate::engine::layout::LabelMap;
use crate::offline::{self, LoadedTake, ModelFrames};

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
        let mut r: Vec<f64> = self
            .residuals_mm
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .collect();
        if r.is_empty() {
            return None;
        }
        Some((quantile(&mut r, 0.5), quantile(&mut r, 0.95)))
    }
}

/// Prepares loaded takes for training. See the module docs.
///
/// # Errors
/// No marker left, unknown reference labels, too few reference markers, or no take shares a
/// marker with the first.
pub fn prepare(takes: &[LoadedTake], options: &PrepOptions) -> Result<PreparedData> {
    let rate_hz = options.rate_hz.unwrap_or(takes[0].take.rate_hz);
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
    let (labels, excluded) = kept_markers(&takes, options.max_missing_share)?;
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
    // 1. The head: decided on the raw frames, template from them (its Procrustes mean shrugs
    //    off rare glitches).
    let raw_missing: Vec<bool> = frames
        .iter()
        .flat_map(|f| f.missing.iter().copied())
        .collect();
    let raw_xyz: Vec<f32> = frames.iter().flat_map(|f| f.xyz.iter().copied()).collect();
    let mut ranges = Vec::with_capacity(frames.len());
    let mut start = 0;
    for f in &frames {
        ranges.push(start..start + f.frames());
        start += f.frames();
    }
    let raw = MarkerFrames {
        xyz: &raw_xyz,
        missing: &raw_missing,
        markers: n,
        takes: &ranges,
    };
    let decision = head::decide(&options.head, &labels, &raw)?;
    let reference = decision.markers;
    let mut head_report = decision.report;
    let head = match reference.len() {
        0 => None,
        _ => Some(
            Stabiliser::fit(&raw_xyz, &raw_missing, n, reference.clone())?
                .reference()
                .clone(),
        ),
    };
    let mut capture = CaptureSettings {
        head,
        max_speed_mm_s: None,
        bounds: None,
    };
    // 2. Speeds and plausible regions measured in head coordinates, then applied.
    let (head_xyz, head_missing, _, _) = run_prep(&frames, n, rate_hz, &capture)?;
    capture.max_speed_mm_s = match options.speed {
        SpeedLimit::Off => None,
        SpeedLimit::MmPerS(v) => Some(v),
        SpeedLimit::Auto => auto_speed(&head_xyz, &head_missing, &frames, n, rate_hz),
    };
    if options.bounds {
        capture.bounds = Some(marker_bounds(&head_xyz, &head_missing, n));
    }
    let (samples, marker_missing, glitches, residuals_mm) =
        run_prep(&frames, n, rate_hz, &capture)?;
    let per_marker = glitches_per_marker(&frames, &marker_missing, n);
    if let Some(h) = &capture.head {
        head_report.residual_mm = reference_residuals(h, &samples, &marker_missing, n)
            .into_iter()
            .map(|(m, r)| (labels[m].clone(), r))
            .collect();
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
        resampled,
        glitches,
        residuals_mm,
    })
}

type PrepRun = (Vec<f32>, Vec<bool>, usize, Vec<f64>);

/// Runs every take through a fresh [`FramePrep`]: positions, per-marker mask, glitches,
/// residuals.
fn run_prep(
    frames: &[ModelFrames],
    n: usize,
    rate_hz: f64,
    capture: &CaptureSettings,
) -> Result<PrepRun> {
    let total: usize = frames.iter().map(ModelFrames::frames).sum();
    let mut xyz = Vec::with_capacity(total * n * 3);
    let mut missing = Vec::with_capacity(total * n);
    let mut glitches = 0;
    let mut residuals = Vec::new();
    for take in frames {
        let mut prep = FramePrep::new(n, rate_hz, capture);
        for f in 0..take.frames() {
            let (p, m) = take.frame(f);
            let out = prep.prepare(p, m)?;
            xyz.extend_from_slice(out.xyz);
            missing.extend_from_slice(out.missing);
            glitches += out.info.glitches;
            if out.info.pose.is_some() && !out.info.pose_held {
                residuals.push(out.info.residual_mm);
            }
        }
    }
    Ok((xyz, missing, glitches, residuals))
}

/// Labels kept, and the labels left out with the share of frames they were missing in.
type KeptMarkers = (Vec<String>, Vec<(String, f64)>);

/// The first take's labels minus the markers missing too often over all takes.
fn kept_markers(takes: &[replay::Take], max_share: f64) -> Result<KeptMarkers> {
    let first = &takes[0].labels;
    let mut missing = vec![0usize; first.len()];
    let mut frames = 0usize;
    for t in takes {
        let map = LabelMap::new(first, &t.labels)?;
        let counts = t.missing_per_marker();
        for (i, src) in map.model_to_take.iter().enumerate() {
            missing[i] += match src {
                Some(j) => counts[*j],
                None => t.n_frames(),
            };
        }
        frames += t.n_frames();
    }
    let mut kept = Vec::new();
    let mut excluded = Vec::new();
    for (label, &gone) in first.iter().zip(&missing) {
        let share = gone as f64 / frames.max(1) as f64;
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
    Ok((kept, excluded))
}

/// RMS distance (mm) of each reference marker from its template place, over the prepared
/// (head-coordinate) frames: how rigid the reference held.
fn reference_residuals(
    head: &ica_core::stabilise::HeadReference,
    xyz: &[f32],
    missing: &[bool],
    n: usize,
) -> Vec<(usize, f64)> {
    let frames = missing.len() / n.max(1);
    // Head coordinates put the template's centroid where the Procrustes fit put it: compare
    // each frame's reference shape, centred, to the centred template.
    let mut sq = vec![0.0f64; head.markers.len()];
    let mut count = vec![0usize; head.markers.len()];
    for f in 0..frames {
        let present: Vec<usize> = (0..head.markers.len())
            .filter(|&k| !missing[f * n + head.markers[k]])
            .collect();
        if present.len() < 3 {
            continue;
        }
        let at = |k: usize, a: usize| f64::from(xyz[(f * n + head.markers[k]) * 3 + a]);
        let mut c = [0.0; 3];
        let mut t = [0.0; 3];
        for &k in &present {
            for a in 0..3 {
                c[a] += at(k, a) / present.len() as f64;
                t[a] += head.template[k][a] / present.len() as f64;
            }
        }
        for &k in &present {
            sq[k] += (0..3)
                .map(|a| (at(k, a) - c[a] - (head.template[k][a] - t[a])).powi(2))
                .sum::<f64>();
            count[k] += 1;
        }
    }
    head.markers
        .iter()
        .enumerate()
        .map(|(k, &m)| (m, (sq[k] / count[k].max(1) as f64).sqrt()))
        .collect()
}
