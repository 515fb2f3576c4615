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

use crate::engine::edit_state::EditState;
use crate::engine::LabelMap;
use crate::offline::analysis::DTW_BAND_SHARE;
use crate::offline::{self, ModelFrames, Projected};

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

/// A take projected under a model, ready to align.
fn project_other(model: &IcaModel, path: &Path) -> Result<Projected> {
    let take = offline::load_take(path)?;
    let map = offline::match_take(model, &take, path)?;
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
struct Plan {
    offsets: Vec<f32>,
    gains: Vec<f32>,
    /// Components replaced by a value per frame each.
    replace: Series,
    /// A second model's components added per frame.
    add: Option<(IcaModel, Series)>,
    /// The live emotion edit (causal low-pass), when `--lowpass` asks for it.
    live: Option<EditState>,
}

fn plan(
    request: &EditRequest,
    model_path: &Path,
    model: &IcaModel,
    projected: &Projected,
    frames: &ModelFrames,
) -> Result<Plan> {
    let m = model.components();
    let mut plan = Plan {
        offsets: vec![0.0; m],
        gains: vec![1.0; m],
        replace: Vec::new(),
        add: None,
        live: None,
    };
    for &(k, v) in &request.translate {
        plan.offsets[check_component(model, k, v, "--translate")?] += v as f32;
    }
    for &(k, g) in &request.gain {
        plan.gains[check_component(model, k, g, "--gain")?] *= g as f32;
    }
    let amount = request.amount;
    if let Some(text) = &request.to_emotion {
        let space = emotion_components(model, model_path)?;
        let (name, point) = target_point(model, text)?;
        if !(0.0..=1.0).contains(&amount) {
            return Err(BadRequest(format!("--amount {amount} is outside 0..1")).into());
        }
        match request.lowpass_s {
            // The live daemon's edit: towards the point from a causal low-pass of each emotion
            // component, exactly as `serve` does with a zero ramp.
            Some(window) => {
                let mut state = EditState::for_model(model, window as f32);
                state.set_ramp(0.0);
                let p: Vec<f32> = point.iter().map(|&v| v as f32).collect();
                state.set_target(&name, &p)?;
                state.set_amount(amount as f32)?;
                plan.live = Some(state);
            }
            None => {
                let n = frames.frames().max(1) as f64;
                let current: Vec<f32> = space
                    .iter()
                    .map(|&k| (projected.component(k).iter().sum::<f64>() / n) as f32)
                    .collect();
                let goal: Vec<f32> = point.iter().map(|&v| v as f32).collect();
                let mut to = vec![0.0f32; space.len()];
                ica_core::model::SpaceTarget::new(model.emotion())
                    .target_into(&current, &goal, &mut to);
                for ((&k, c), t) in space.iter().zip(&current).zip(&to) {
                    plan.offsets[k] += (amount as f32) * (t - c);
                }
            }
        }
    }
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
        plan.replace = axes.into_iter().zip(series).collect();
        for k in shifted {
            let mean = |p: &Projected| {
                p.component(k).iter().sum::<f64>() / p.component(k).len().max(1) as f64
            };
            plan.offsets[k] += (mean(&other_u) - mean(projected)) as f32;
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
        plan.add = Some((model2, space2.into_iter().zip(series).collect()));
    }
    Ok(plan)
}

/// Edits `take` under `model` (read from `model_path`, named in errors) as `request` asks and
/// returns the edited take:
/// the model's markers edited (gaps filled from the model unless `keep_gaps`), then the
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
    let map = offline::match_take(model, take, take_path)?;
    let frames = offline::to_model_order(take, &map);
    let projected = offline::project_take(model, &frames)?;
    let mut plan = plan(request, model_path, model, &projected, &frames)?;
    let mut frame_edit = FrameEdit::identity(model.components());
    for k in 0..plan.offsets.len() {
        frame_edit.set_offset(k, plan.offsets[k])?;
        frame_edit.set_gain(k, plan.gains[k])?;
    }
    let mut live = plan.live.take();
    let dt = (1.0 / model.rate_hz()) as f32;
    let mut edited = offline::resynthesise(model, &projected, |f, u| {
        for (k, values) in &plan.replace {
            frame_edit.set_override(*k, Some(values[f] as f32))?;
        }
        frame_edit.apply(u)?;
        if let Some(state) = live.as_mut() {
            state.apply(dt, u);
        }
        Ok(())
    })?;
    if let Some((model2, added)) = &plan.add {
        let second = Projector::new(model2);
        let channels = model.channels();
        for (f, frame) in edited.chunks_exact_mut(channels).enumerate() {
            for (k2, values) in added {
                second.add_component_into(*k2, values[f] as f32, frame)?;
            }
        }
    }
    assemble(
        take,
        model.labels(),
        &map,
        &frames,
        edited,
        request.keep_gaps,
    )
}

/// The output take: the model's markers edited (gaps filled from the model unless `keep_gaps`),
/// followed by the take's extra markers unchanged, so nothing the user gave is lost.
fn assemble(
    take: &Take,
    model_labels: &[String],
    map: &LabelMap,
    frames: &ModelFrames,
    edited: Vec<f32>,
    keep_gaps: bool,
) -> Result<Take> {
    let model_markers = map.model_to_take.len();
    let mut labels: Vec<String> = Vec::with_capacity(model_markers + map.extra.len());
    labels.extend_from_slice(model_labels);
    labels.extend(map.extra.iter().map(|&t| take.labels[t].clone()));
    let mut out = Take::new(labels, take.rate_hz, take.first_frame);
    out.source_units = take.source_units;
    let width = out.n_markers();
    let mut xyz = vec![0.0f32; width * 3];
    let mut missing = vec![false; width];
    for f in 0..take.n_frames() {
        let (_, model_missing) = frames.frame(f);
        xyz[..model_markers * 3]
            .copy_from_slice(&edited[f * model_markers * 3..(f + 1) * model_markers * 3]);
        for i in 0..model_markers {
            missing[i] = keep_gaps && model_missing[i];
        }
        for (j, &t) in map.extra.iter().enumerate() {
            let slot = model_markers + j;
            xyz[slot * 3..slot * 3 + 3].copy_from_slice(&take.frame(f)[t * 3..t * 3 + 3]);
            missing[slot] = take.is_missing(f, t);
        }
        if xyz.iter().any(|v| !v.is_finite()) {
            bail!("frame {f}: the edit produced a non-finite position");
        }
        out.push_frame(&xyz, &missing);
    }
    Ok(out)
}
