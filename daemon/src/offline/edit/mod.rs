//! Edits of a take in component space, by index or by emotion, as `emoshift edit` runs them:
//! an [`EditRequest`] planned against a model and applied frame by frame ([`edit_take`]).
//!
//! - `--translate k=a`, `--gain k=g`: raw edits (section 5, *Translate*).
//! - `--to-emotion NAME [--amount x]`: translate every emotion component `E` of the model's
//!   emotion space by `x · (point[NAME]_E − mean of the take's u_E)`; a blend
//!   `--to-emotion sad:0.5,angry:0.5` targets the weighted mean of the points. With
//!   `--lowpass S`, the live daemon's edit instead, `x · (point_E − lowpass_S(u_E))`, causal,
//!   frame by frame.
//! - `--replace-emotion-from OTHER`: *Copy & Replace*, the other take's emotion axes,
//!   DTW-aligned to this take on the other components; emotion components that also carry
//!   speech take only the other take's level.
//! - `--add-emotion-from OTHER --other-model m2.json`: *Copy & Add*, `x = mean₁ + M₁u₁ +
//!   Σ_E M₂ (u₂ᵀe_E) e_E` over the second model's emotion components, `u₂` the other take
//!   under the second model, aligned likewise.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};
use ica_core::dtw;
use ica_core::edit::FrameEdit;
use ica_core::model::IcaModel;
use ica_core::project::Projector;
use replay::Take;

mod editor;
mod output;
mod streamed;

pub(crate) use self::editor::FrameEditor;
pub(crate) use self::output::Output;
pub use self::streamed::{edit_file, EditSummary};
use crate::offline::analysis::DTW_BAND_SHARE;
use crate::offline::{self, ModelFrames, Projected};
use engine::edit_state::EditState;

/// What to do to a take; every field is optional and they combine.
#[derive(Debug, Clone, Default)]
pub struct EditRequest {
    /// Raw translations: (component, offset).
    pub translate: Vec<(usize, f64)>,
    /// Gains: (component, gain).
    pub gain: Vec<(usize, f64)>,
    /// Towards an emotion (`NAME`) or a blend (`NAME:W,NAME:W`).
    pub to_emotion: Option<String>,
    /// How far towards it, 0..1.
    pub amount: f64,
    /// Edit as the live daemon does, with this low-pass window (seconds).
    pub lowpass_s: Option<f64>,
    /// Copy & Replace from this take.
    pub replace_from: Option<PathBuf>,
    /// Copy & Add from this take, under this second model.
    pub add_from: Option<(PathBuf, PathBuf)>,
    /// Keep the gaps of the input instead of filling them from the model.
    pub keep_gaps: bool,
    /// Write only the frames from this one (`--start`; the take's first when `None`).
    pub start: Option<crate::offline::trim::FrameOrTime>,
    /// ... to this one, inclusive (`--end`; the take's last when `None`).
    pub end: Option<crate::offline::trim::FrameOrTime>,
}

/// A request the model cannot carry out as asked: a command-line mistake, not a failure.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct BadRequest(pub String);

fn check_component(model: &IcaModel, k: usize, value: f64, flag: &str) -> Result<usize> {
    if k >= model.components() {
        return Err(BadRequest(format!(
            "{flag} {k}={value}: the model has {} components (0..{})",
            model.components(),
            model.components().saturating_sub(1)
        ))
        .into());
    }
    Ok(k)
}

/// The emotion components of a model, or a clear error telling how to get them.
fn emotion_components(model: &IcaModel, path: &Path) -> Result<Vec<usize>> {
    let space = model.emotion().space_components();
    if space.is_empty() {
        bail!(
            "{}: the model has no emotion component yet; run `emoshift analyze --write-model` on a paired session first",
            path.display()
        );
    }
    Ok(space)
}

/// The target of `--to-emotion`: `NAME`, or a blend `NAME:W,NAME:W...`; returns the name the
/// edit reports and the point in the emotion space.
pub(crate) fn target_point(model: &IcaModel, text: &str) -> Result<(String, Vec<f64>)> {
    let mut weights: Vec<(&str, f64)> = Vec::new();
    for part in text.split(',') {
        let (name, weight) = match part.split_once(':') {
            Some((n, w)) => {
                let w: f64 = w.trim().parse().map_err(|_| {
                    BadRequest(format!(
                        "--to-emotion {text}: weight {w:?} of {n} is not a number"
                    ))
                })?;
                (n.trim(), w)
            }
            None => (part.trim(), 1.0),
        };
        weights.push((name, weight));
    }
    let point = model
        .emotion()
        .blend(&weights)
        .map_err(|e| BadRequest(format!("--to-emotion {text}: {e}")))?;
    Ok((text.to_string(), point))
}

/// A take projected under a model, ready to align. It must have at least half the model's
/// markers: its emotion is copied whole, and from fewer markers it would be mostly guessed.
fn project_other(model: &IcaModel, path: &Path) -> Result<Projected> {
    let take = offline::load_take(path)?;
    let map = offline::match_take(model, &take, path)?;
    let absent = map.absent().count();
    let markers = model.markers();
    if 2 * absent > markers {
        return Err(BadRequest(format!(
            "{} has only {} of the model's {markers} markers: the emotion to copy needs at least half of them",
            path.display(),
            markers - absent
        ))
        .into());
    }
    offline::project_take(model, &offline::to_model_order(&take, &map))
}

/// Components `ks` of `other`, resampled onto `this` take's timeline by DTW on the other
/// components (each take's means removed); one series per component of `ks`.
fn aligned_components(this: &Projected, other: &Projected, ks: &[usize]) -> Result<Vec<Vec<f64>>> {
    let m = this.m;
    let rest: Vec<usize> = (0..m).filter(|j| !ks.contains(j)).collect();
    // With every component in `ks`, align on all of them.
    let on = if rest.is_empty() {
        (0..m).collect()
    } else {
        rest
    };
    let pick = |p: &Projected| -> Vec<f64> {
        p.u.chunks_exact(m)
            .flat_map(|row| on.iter().map(move |&j| f64::from(row[j])))
            .collect()
    };
    let (a, b) = (pick(this), pick(other));
    let longest = (a.len().max(b.len()) / on.len()) as f64;
    let band = (longest * DTW_BAND_SHARE).ceil() as usize;
    let at = dtw::warp_onto(&a, &b, on.len(), Some(band))?;
    Ok(ks
        .iter()
        .map(|&k| dtw::resample_at(&other.component(k), &at))
        .collect())
}

/// Per-frame values of some components: (component, one value per frame).
type Series = Vec<(usize, Vec<f64>)>;

/// The per-frame edit plan.
pub(crate) struct Plan {
    offsets: Vec<f32>,
    gains: Vec<f32>,
    /// Components replaced by a value per frame each.
    replace: Series,
    /// A second model's components added per frame.
    add: Option<(IcaModel, Series)>,
    /// The live emotion edit (causal low-pass), when `--lowpass` asks for it.
    live: Option<EditState>,
    /// `--to-emotion` from the take's mean: the point and how far; waits for the take's
    /// component sums ([`Plan::settle`]).
    toward: Option<(Vec<f32>, f32)>,
}

/// Sums of each component over a take's frames, in frame order, for the take's mean: the one
/// accumulation of the whole-take and the streaming edits, so their means are the same bits.
#[derive(Debug, Clone)]
pub(crate) struct ComponentSums {
    sums: Vec<f64>,
    frames: usize,
}

impl ComponentSums {
    pub(crate) fn new(components: usize) -> Self {
        // -0.0 is the identity of float addition, as in `Iterator::sum`.
        ComponentSums {
            sums: vec![-0.0; components],
            frames: 0,
        }
    }

    /// Adds one frame's components.
    pub(crate) fn add(&mut self, u: &[f32]) {
        for (s, &v) in self.sums.iter_mut().zip(u) {
            *s += f64::from(v);
        }
        self.frames += 1;
    }

    fn mean(&self, k: usize) -> f32 {
        (self.sums[k] / self.frames.max(1) as f64) as f32
    }
}

/// Checks a request against the model and plans what needs no take: the raw edits, the live
/// emotion edit, and the target of a mean-based one.
///
/// # Errors
/// A [`BadRequest`], or a model without an emotion space when the request needs one.
pub(crate) fn plan(request: &EditRequest, model_path: &Path, model: &IcaModel) -> Result<Plan> {
    let m = model.components();
    let mut plan = Plan {
        offsets: vec![0.0; m],
        gains: vec![1.0; m],
        replace: Vec::new(),
        add: None,
        live: None,
        toward: None,
    };
    for &(k, v) in &request.translate {
        plan.offsets[check_component(model, k, v, "--translate")?] += v as f32;
    }
    for &(k, g) in &request.gain {
        plan.gains[check_component(model, k, g, "--gain")?] *= g as f32;
    }
    if request.to_emotion.is_some() && request.replace_from.is_some() {
        // Copy & Replace sets the emotion components to the other take's: a target for them
        // would be overwritten without a word.
        return Err(BadRequest(
            "--to-emotion and --replace-emotion-from both set the emotion: give one".into(),
        )
        .into());
    }
    let amount = request.amount;
    if let Some(text) = &request.to_emotion {
        emotion_components(model, model_path)?;
        let (name, point) = target_point(model, text)?;
        if !(0.0..=1.0).contains(&amount) {
            return Err(BadRequest(format!("--amount {amount} is outside 0..1")).into());
        }
        let goal: Vec<f32> = point.iter().map(|&v| v as f32).collect();
        match request.lowpass_s {
            // The live daemon's edit: towards the point from a causal low-pass of each emotion
            // component, exactly as `serve` does with a zero ramp.
            Some(window) => {
                let mut state = EditState::for_model(model, window as f32);
                state.set_ramp(0.0);
                state.set_target(&name, &goal)?;
                state.set_amount(amount as f32)?;
                plan.live = Some(state);
            }
            None => plan.toward = Some((goal, amount as f32)),
        }
    }
    Ok(plan)
}

impl Plan {
    /// Whether the plan needs the take's component means ([`Plan::settle`]) before editing.
    pub(crate) fn needs_means(&self) -> bool {
        self.toward.is_some()
    }

    /// Turns a mean-based `--to-emotion` into offsets, from the take's component sums: the
    /// take's mean read in the emotion space, moved to its target there.
    pub(crate) fn settle(&mut self, model: &IcaModel, sums: &ComponentSums) {
        let Some((goal, amount)) = self.toward.take() else {
            return;
        };
        let m = model.components();
        let mut space = ica_core::model::SpaceTarget::new(model.emotion(), m);
        let means: Vec<f32> = (0..m).map(|k| sums.mean(k)).collect();
        let mut current = vec![0.0f32; space.dims()];
        space.coordinates_into(&means, &mut current);
        let mut to = vec![0.0f32; space.dims()];
        space.target_into(&current, &goal, &mut to);
        let delta: Vec<f32> = to.iter().zip(&current).map(|(t, c)| t - c).collect();
        space.move_into(&delta, amount, &mut self.offsets);
    }

    /// Copy & Replace and Copy & Add, which align another take to the whole of this one.
    fn copies(
        &mut self,
        request: &EditRequest,
        (model_path, model): (&Path, &IcaModel),
        projected: &Projected,
        frames: &ModelFrames,
    ) -> Result<()> {
        if let Some(other) = &request.replace_from {
            // The emotion axes take the other take's series (the paper's Copy & Replace); the
            // other emotion components also follow what is said, so they only take the other
            // take's level: their own motion stays.
            let space = emotion_components(model, model_path)?;
            let (axes, shifted): (Vec<usize>, Vec<usize>) = space
                .iter()
                .partition(|&&k| model.roles()[k] == ica_core::model::Role::Emotion);
            let other_u = project_other(model, other)?;
            let series = aligned_components(projected, &other_u, &axes)?;
            self.replace = axes.into_iter().zip(series).collect();
            for k in shifted {
                let mean = |p: &Projected| {
                    p.component(k).iter().sum::<f64>() / p.component(k).len().max(1) as f64
                };
                self.offsets[k] += (mean(&other_u) - mean(projected)) as f32;
            }
        }
        if let Some((other, path)) = &request.add_from {
            let model2 = crate::offline::load_model(path)?;
            if model2.labels() != model.labels() {
                bail!(
                    "{}: Copy & Add needs both models to have the same markers in the same order",
                    path.display()
                );
            }
            let space2 = emotion_components(&model2, path)?;
            let this2 = offline::project_take(&model2, frames)?;
            let other_u = project_other(&model2, other)?;
            let series = aligned_components(&this2, &other_u, &space2)?;
            self.add = Some((model2, space2.into_iter().zip(series).collect()));
        }
        Ok(())
    }

    /// The per-frame editor of this plan.
    ///
    /// # Errors
    /// An offset or gain the edit refuses (not finite).
    pub(crate) fn editor(&mut self, model: &IcaModel) -> Result<FrameEditor> {
        let mut edit = FrameEdit::identity(model.components());
        for k in 0..self.offsets.len() {
            edit.set_offset(k, self.offsets[k])?;
            edit.set_gain(k, self.gains[k])?;
        }
        Ok(FrameEditor {
            edit,
            live: self.live.take(),
            dt: (1.0 / model.rate_hz()) as f32,
            replace: std::mem::take(&mut self.replace),
        })
    }
}

/// Edits `take` under `model` (read from `model_path`, named in errors) as `request` asks and
/// returns the edited take, holding it whole: the path of Copy & Replace and Copy & Add, which
/// align another take to all of this one ([`crate::offline::streamed`] edits the rest).
/// The model's markers edited (gaps filled from the model unless `keep_gaps`), then the
/// take's extra markers unchanged.
///
/// # Errors
/// A request the model cannot carry out ([`BadRequest`]), a take sharing no marker with the
/// model, an unreadable second take or model, a non-finite result.
pub fn edit_take(
    model: &IcaModel,
    model_path: &Path,
    take: &Take,
    take_path: &Path,
    request: &EditRequest,
) -> Result<Take> {
    let mut plan = plan(request, model_path, model)?;
    let map = offline::match_take(model, take, take_path)?;
    let frames = offline::to_model_order(take, &map);
    let projected = offline::project_take(model, &frames)?;
    let mut sums = ComponentSums::new(model.components());
    for u in projected.u.chunks_exact(projected.m) {
        sums.add(u);
    }
    plan.settle(model, &sums);
    plan.copies(request, (model_path, model), &projected, &frames)?;
    let mut editor = plan.editor(model)?;
    let mut edited = offline::resynthesise(model, &projected, |f, u| editor.apply(f, u))?;
    if let Some((model2, added)) = &plan.add {
        let second = Projector::new(model2);
        let channels = model.channels();
        for (f, frame) in edited.chunks_exact_mut(channels).enumerate() {
            for (k2, values) in added {
                second.add_component_into(*k2, values[f] as f32, frame)?;
            }
        }
    }
    let mut out = Output::new(take, model.labels(), &map);
    let n = map.model_to_take.len();
    for f in 0..take.n_frames() {
        let (_, model_missing) = frames.frame(f);
        let edited = &edited[f * n * 3..(f + 1) * n * 3];
        let source = (take.frame(f), take.frame_missing(f));
        out.push_frame(f, source, (edited, model_missing), request.keep_gaps)?;
    }
    Ok(out.take)
}
