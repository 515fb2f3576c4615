//! A paired session cut from real captures, with a known emotion-like signal (issue 34).
//!
//! No public capture is labelled with emotion, so the emotion edit is tested on real faces
//! this way: the captures are cut into "sentences" (consecutive windows of
//! [`InjectParams::sentence_s`]), and every sentence is taken once per *level*. Each take of a
//! sentence is its window with its ends moved by up to [`InjectParams::jitter_s`] and its pace
//! changed by up to [`InjectParams::pace_spread`] (so no two takes of a sentence are the same
//! frames, and pairs need aligning), plus a known field in head coordinates:
//! `level · field`, level `i / (levels − 1)` for the `i`-th level. Each level is an "emotion"
//! (`level1`, `level2`, ...), so the session is paired as a real one is: the same content in
//! every emotion. The field is smooth over the face (a random affine field and a few bumps,
//! without any rigid part), [`InjectParams::field_mm`] RMS over the face markers at the top
//! level and zero on the head reference; it turns with the head (the rotation of the reference
//! markers' pose, frame by frame), and gaps stay gaps.
//!
//! The truth of editing a take to another level is the same cut at that level
//! ([`InjectedSession::render`]): the known field, turned with the head, times the level
//! change, on the samples the take has.

mod field;
mod write;

use anyhow::{bail, Context, Result};
use ica_core::stabilise::{Pose, Stabiliser};
use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use replay::Take;
use serde::Serialize;

pub use write::{write_session, InjectTruth, TRUTH_FILE};

/// Default number of levels.
pub const DEFAULT_LEVELS: usize = 3;
/// Default RMS of the field at the top level over the face markers, mm.
pub const DEFAULT_FIELD_MM: f64 = 3.0;
/// Default length of a sentence, seconds.
pub const DEFAULT_SENTENCE_S: f64 = 5.0;
/// Default largest move of each end of a take, seconds.
pub const DEFAULT_JITTER_S: f64 = 0.3;
/// Default largest pace change of a take (±).
pub const DEFAULT_PACE_SPREAD: f64 = 0.08;

/// How the session is cut and what is injected.
#[derive(Debug, Clone, PartialEq)]
pub struct InjectParams {
    /// Seed of the field, the cuts and the paces.
    pub seed: u64,
    /// Levels ("emotions"), at least 2.
    pub levels: usize,
    /// RMS of the field at the top level over the face markers, mm.
    pub field_mm: f64,
    /// Length of a sentence, seconds.
    pub sentence_s: f64,
    /// Largest move of each end of a take, seconds.
    pub jitter_s: f64,
    /// Largest pace change of a take (±, 0.08 = 8 %).
    pub pace_spread: f64,
}

impl Default for InjectParams {
    fn default() -> InjectParams {
        InjectParams {
            seed: 1,
            levels: DEFAULT_LEVELS,
            field_mm: DEFAULT_FIELD_MM,
            sentence_s: DEFAULT_SENTENCE_S,
            jitter_s: DEFAULT_JITTER_S,
            pace_spread: DEFAULT_PACE_SPREAD,
        }
    }
}

/// One take of the session: where it was cut and at what level.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Cut {
    /// Take name (file stem), e.g. `s03_level2`.
    pub name: String,
    /// Sentence id.
    pub sentence: String,
    /// Emotion (level) name.
    pub emotion: String,
    /// Level, 0 to 1.
    pub level: f64,
    /// Index of the capture it was cut from.
    pub capture: usize,
    /// First capture frame (fractional frames are interpolated).
    pub start: f64,
    /// Capture frames per take frame (1 = the capture's pace).
    pub step: f64,
    /// Frames of the take.
    pub frames: usize,
}

/// One capture with its head pose per frame.
#[derive(Debug, Clone)]
struct Capture {
    name: String,
    take: Take,
    poses: Vec<Pose>,
}

/// Real captures cut into a paired session with a known field. See the module docs.
#[derive(Debug, Clone)]
pub struct InjectedSession {
    params: InjectParams,
    captures: Vec<Capture>,
    /// Field at the top level, head coordinates, markers x 3 (mm).
    field: Vec<f64>,
    head: Vec<String>,
    cuts: Vec<Cut>,
}

impl InjectedSession {
    /// Cuts `captures` (name, take; all with the same markers and rate) into a session, the
    /// field in the frame of the `head` markers (empty: world coordinates).
    ///
    /// # Errors
    /// Bad parameters, captures whose markers or rates differ, a head marker the captures do
    /// not have, a head reference that cannot be fitted, captures too short for a sentence.
    pub fn build(
        captures: Vec<(String, Take)>,
        head: &[String],
        params: &InjectParams,
    ) -> Result<InjectedSession> {
        check_params(params)?;
        let Some((first_name, first)) = captures.first() else {
            bail!("no capture to cut");
        };
        for (name, take) in &captures[1..] {
            if take.labels != first.labels || take.rate_hz != first.rate_hz {
                bail!(
                    "{name} has other markers or another rate than {first_name}: the captures of one session must share both"
                );
            }
        }
        let head_idx = head
            .iter()
            .map(|l| {
                first
                    .marker_index(l)
                    .with_context(|| format!("head reference marker {l:?} is not in the captures"))
            })
            .collect::<Result<Vec<usize>>>()?;
        let captures = captures
            .into_iter()
            .map(|(name, take)| {
                let poses = poses(&take, &head_idx)
                    .with_context(|| format!("{name}: cannot fit the head reference"))?;
                Ok(Capture { name, take, poses })
            })
            .collect::<Result<Vec<Capture>>>()?;
        let rest = field::rest_in_head(&captures[0].take, &captures[0].poses);
        let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
        let field = field::smooth_field(&rest, &head_idx, params.field_mm, &mut rng);
        let cuts = cut(&captures, params, &mut rng);
        if cuts.is_empty() {
            bail!(
                "the captures are shorter than one {} s sentence: give --sentence-s a shorter length",
                params.sentence_s
            );
        }
        Ok(InjectedSession {
            params: params.clone(),
            captures,
            field,
            head: head.to_vec(),
            cuts,
        })
    }

    /// The takes, sentence-major.
    pub fn cuts(&self) -> &[Cut] {
        &self.cuts
    }

    /// The level names, lowest first.
    pub fn level_names(&self) -> Vec<String> {
        (1..=self.params.levels)
            .map(|i| format!("level{i}"))
            .collect()
    }

    /// The level (0 to 1) of a level name.
    pub fn level_of(&self, name: &str) -> Option<f64> {
        let i = self.level_names().iter().position(|n| n == name)?;
        Some(i as f64 / (self.params.levels - 1) as f64)
    }

    /// The parameters.
    pub fn params(&self) -> &InjectParams {
        &self.params
    }

    /// `cut` rendered at `level` (0 to 1): its frames of the capture, resampled at its pace,
    /// with `level · field` added in head coordinates to every present face marker.
    pub fn render(&self, cut: &Cut, level: f64) -> Take {
        let capture = &self.captures[cut.capture];
        let source = &capture.take;
        let n = source.n_markers();
        let mut take = Take::new(source.labels.clone(), source.rate_hz, 1);
        let (mut xyz, mut missing) = (vec![0.0f32; n * 3], vec![false; n]);
        let last = source.n_frames() - 1;
        for f in 0..cut.frames {
            let t = (cut.start + f as f64 * cut.step).clamp(0.0, last as f64);
            let (lo, hi) = (t.floor() as usize, (t.ceil() as usize).min(last));
            let w = (t - lo as f64) as f32;
            let rotation = capture.poses[if w < 0.5 { lo } else { hi }].rotation;
            for m in 0..n {
                missing[m] = source.is_missing(lo, m) || source.is_missing(hi, m);
                let offset = rotation
                    * Vector3::new(
                        self.field[m * 3],
                        self.field[m * 3 + 1],
                        self.field[m * 3 + 2],
                    )
                    * level;
                for a in 0..3 {
                    let (p, q) = (source.frame(lo)[m * 3 + a], source.frame(hi)[m * 3 + a]);
                    xyz[m * 3 + a] = p + w * (q - p) + offset[a] as f32;
                }
            }
            take.push_frame(&xyz, &missing);
        }
        take
    }
}

fn check_params(p: &InjectParams) -> Result<()> {
    if p.levels < 2 {
        bail!(
            "--levels {}: need at least 2 levels to edit between",
            p.levels
        );
    }
    let positive = |v: f64| v.is_finite() && v > 0.0;
    if !positive(p.field_mm) || !positive(p.sentence_s) {
        bail!(
            "--field-mm {} and --sentence-s {} must be above 0",
            p.field_mm,
            p.sentence_s
        );
    }
    if !(p.jitter_s.is_finite() && p.jitter_s >= 0.0 && p.jitter_s < p.sentence_s / 4.0) {
        bail!(
            "--jitter-s {}: expected 0 to a quarter of the sentence",
            p.jitter_s
        );
    }
    if !(p.pace_spread.is_finite() && (0.0..0.5).contains(&p.pace_spread)) {
        bail!("--pace-spread {}: expected 0 to 0.5", p.pace_spread);
    }
    Ok(())
}

/// The head pose of every frame (identity without a head reference; the last pose held
/// through frames with too few reference markers).
fn poses(take: &Take, head: &[usize]) -> Result<Vec<Pose>> {
    if head.is_empty() {
        return Ok(vec![Pose::identity(); take.n_frames()]);
    }
    let n = take.n_markers();
    let mut st = Stabiliser::fit(&take.positions, &take.missing, n, head.to_vec())?;
    Ok((0..take.n_frames())
        .map(|f| st.estimate(take.frame(f), take.frame_missing(f)).pose)
        .collect())
}

/// Every sentence window of every capture, taken once per level.
fn cut(captures: &[Capture], p: &InjectParams, rng: &mut impl Rng) -> Vec<Cut> {
    let mut cuts = Vec::new();
    let mut sentence = 0;
    for (c, capture) in captures.iter().enumerate() {
        let rate = capture.take.rate_hz;
        let frames = capture.take.n_frames();
        let window = p.sentence_s * rate;
        let jitter = p.jitter_s * rate;
        let count = (frames as f64 / window).floor() as usize;
        for k in 0..count {
            sentence += 1;
            for level in 0..p.levels {
                let mut draw = |r: f64| {
                    if r > 0.0 {
                        rng.random_range(-r..r)
                    } else {
                        0.0
                    }
                };
                let start = (k as f64 * window + draw(jitter)).max(0.0);
                let end = ((k + 1) as f64 * window + draw(jitter)).min((frames - 1) as f64);
                let step = 1.0 + draw(p.pace_spread);
                let emotion = format!("level{}", level + 1);
                cuts.push(Cut {
                    name: format!("s{sentence:02}_{emotion}"),
                    sentence: format!("s{sentence:02}"),
                    emotion,
                    level: level as f64 / (p.levels - 1) as f64,
                    capture: c,
                    start,
                    step,
                    frames: ((end - start) / step).floor() as usize + 1,
                });
            }
        }
    }
    cuts
}
