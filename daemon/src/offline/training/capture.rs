//! What preparing learns from the capture before it prepares any frame: the head reference and
//! its template, then the glitch limits (speed, plausible regions) measured in head
//! coordinates. The in-memory path learns them from every frame; streaming training from a
//! bounded sample of whole stretches of takes ([`super::streamed`]), the same function on fewer
//! frames.

use anyhow::Result;
use ica_core::model::CaptureSettings;
use ica_core::quality::HeadReport;
use ica_core::stabilise::{HeadReference, MarkerFrames, Stabiliser, TakeFrames};

use super::glitches::{auto_speed, marker_bounds};
use super::{head, run_prep, PrepOptions, SpeedLimit};
use crate::offline::ModelFrames;

/// The capture settings learned, with the head decision.
#[derive(Debug, Clone)]
pub(super) struct Learned {
    /// Head reference, speed limit and plausible regions.
    pub capture: CaptureSettings,
    /// Reference marker indices (empty without stabilisation).
    pub reference: Vec<usize>,
    /// How the head was decided.
    pub head: HeadReport,
}

/// Learns the capture settings from `frames` (stretches of takes, in model marker order):
/// [`decide_head`], then [`learn_limits`].
///
/// # Errors
/// Named reference markers that do not resolve, too few of them, or a template that cannot be
/// fitted.
pub(super) fn learn(
    frames: &[ModelFrames],
    labels: &[String],
    excluded: &[(String, f64)],
    rate_hz: f64,
    options: &PrepOptions,
) -> Result<Learned> {
    let decided = decide_head(frames, labels, excluded, options)?;
    let (learned, _) = learn_limits(frames, labels.len(), rate_hz, options, decided)?;
    Ok(learned)
}

/// The frames the glitch limits were measured on, in the decided head's coordinates and
/// before any glitch check (there were no limits yet): what preparing them again would
/// stabilise, so a pass over the same frames can run the glitch checks alone.
#[derive(Debug, Clone, Default)]
pub(super) struct HeadFrames {
    /// Positions, frames x markers x 3 (head coordinates when stabilised).
    pub xyz: Vec<f32>,
    /// Missing flags (absent or not finite), frames x markers.
    pub missing: Vec<bool>,
    /// Stabilisation residual (mm) of each frame whose pose was estimated, in frame order.
    pub residuals: Vec<f64>,
}

/// The head decision, and the head reference it makes (none without stabilisation).
#[derive(Debug, Clone)]
pub(super) struct DecidedHead {
    head: Option<HeadReference>,
    reference: Vec<usize>,
    report: HeadReport,
}

/// Decides the head on the raw `frames`; its template is the decision's own Procrustes mean
/// over the sample it assessed the reference on (it shrugs off rare glitches, and the sample's
/// glitches are masked).
///
/// # Errors
/// As [`learn`].
pub(super) fn decide_head(
    frames: &[ModelFrames],
    labels: &[String],
    excluded: &[(String, f64)],
    options: &PrepOptions,
) -> Result<DecidedHead> {
    // The takes as they lie: the search reads a bounded sample of their frames.
    let takes: Vec<TakeFrames<'_>> = (frames.iter())
        .map(|f| TakeFrames {
            xyz: &f.xyz,
            missing: &f.missing,
        })
        .collect();
    let raw = MarkerFrames {
        takes: &takes,
        markers: labels.len(),
    };
    let decision = head::decide(&options.head, labels, excluded, &raw)?;
    let reference = decision.markers;
    let head = match reference.len() {
        0 => None,
        _ => Some(
            Stabiliser::new(HeadReference {
                markers: reference.clone(),
                template: decision.template,
            })?
            .reference()
            .clone(),
        ),
    };
    Ok(DecidedHead {
        head,
        reference,
        report: decision.report,
    })
}

/// The glitch limits (speeds and plausible regions) measured on `frames` (`n` markers) in the
/// coordinates of the `decided` head, and those frames in them.
///
/// # Errors
/// Preparing the frames failing.
pub(super) fn learn_limits(
    frames: &[ModelFrames],
    n: usize,
    rate_hz: f64,
    options: &PrepOptions,
    decided: DecidedHead,
) -> Result<(Learned, HeadFrames)> {
    let mut capture = CaptureSettings {
        head: decided.head,
        max_speed_mm_s: None,
        bounds: None,
    };
    let (head_xyz, head_missing, _, residuals) = run_prep(frames, n, rate_hz, &capture)?;
    // The two are independent: at once on the current rayon pool.
    let (speed, bounds) = rayon::join(
        || match options.speed {
            SpeedLimit::Off => None,
            SpeedLimit::MmPerS(v) => Some(v),
            SpeedLimit::Auto => auto_speed(&head_xyz, &head_missing, frames, n, rate_hz),
        },
        || {
            options
                .bounds
                .then(|| marker_bounds(&head_xyz, &head_missing, n))
        },
    );
    capture.max_speed_mm_s = speed;
    capture.bounds = bounds;
    let learned = Learned {
        capture,
        reference: decided.reference,
        head: decided.report,
    };
    let frames = HeadFrames {
        xyz: head_xyz,
        missing: head_missing,
        residuals,
    };
    Ok((learned, frames))
}

/// RMS distance (mm) of each reference marker from its template place, over prepared
/// (head-coordinate) frames added one at a time: how rigid the reference held.
#[derive(Debug, Clone)]
pub(crate) struct RefResiduals<'a> {
    head: &'a HeadReference,
    sq: Vec<f64>,
    count: Vec<usize>,
    present: Vec<usize>,
}

impl<'a> RefResiduals<'a> {
    pub(crate) fn new(head: &'a HeadReference) -> Self {
        let k = head.markers.len();
        Self {
            head,
            sq: vec![0.0; k],
            count: vec![0; k],
            present: Vec::with_capacity(k),
        }
    }

    /// Adds a prepared frame (markers x 3, and its marker mask).
    pub(crate) fn add_frame(&mut self, xyz: &[f32], missing: &[bool]) {
        let head = self.head;
        self.present.clear();
        self.present
            .extend((0..head.markers.len()).filter(|&k| !missing[head.markers[k]]));
        if self.present.len() < 3 {
            return;
        }
        // Head coordinates put the template's centroid where the Procrustes fit put it:
        // compare the frame's reference shape, centred, to the centred template.
        let at = |k: usize, a: usize| f64::from(xyz[head.markers[k] * 3 + a]);
        let share = self.present.len() as f64;
        let mut c = [0.0; 3];
        let mut t = [0.0; 3];
        for &k in &self.present {
            for a in 0..3 {
                c[a] += at(k, a) / share;
                t[a] += head.template[k][a] / share;
            }
        }
        for &k in &self.present {
            self.sq[k] += (0..3)
                .map(|a| (at(k, a) - c[a] - (head.template[k][a] - t[a])).powi(2))
                .sum::<f64>();
            self.count[k] += 1;
        }
    }

    /// Each reference marker's RMS residual, by label.
    pub(crate) fn by_label(&self, labels: &[String]) -> std::collections::BTreeMap<String, f64> {
        self.head
            .markers
            .iter()
            .enumerate()
            .map(|(k, &m)| {
                let rms = (self.sq[k] / self.count[k].max(1) as f64).sqrt();
                (labels[m].clone(), rms)
            })
            .collect()
    }
}
