//! `emoshift edit`: component-space edits of a take, by index or by emotion name.
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

use std::path::Path;

use anyhow::{bail, Context, Result};
use ica_core::edit::FrameEdit;
use ica_core::model::IcaModel;
use ica_core::project::Projector;
use replay::Take;

use crate::cli::{EditArgs, KeyValue};
use crate::engine::edit_state::EditState;
use crate::exit::UsageError;
use crate::offline::{self, ModelFrames, Projected};

fn check_component(model: &IcaModel, kv: &KeyValue, flag: &str) -> Result<usize> {
    if kv.key >= model.components() {
        return Err(UsageError(format!(
            "{flag} {}={}: the model has {} components (0..{})",
            kv.key,
            kv.value,
            model.components(),
            model.components().saturating_sub(1)
        ))
        .into());
    }
    Ok(kv.key)
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
                    UsageError(format!(
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
        .map_err(|e| UsageError(format!("--to-emotion {text}: {e}")))?;
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
    let strip = |p: &Projected| -> Vec<f64> {
        p.u.chunks_exact(m)
            .flat_map(|row| {
                (0..m)
                    .filter(|j| !ks.contains(j))
                    .map(move |j| f64::from(row[j]))
            })
            .collect()
    };
    let rest = m - ks.len();
    let dim = rest.max(1);
    let (a, b) = if rest == 0 {
        (this.as_f64(), other.as_f64())
    } else {
        (strip(this), strip(other))
    };
    let dim = if rest == 0 { m } else { dim };
    let n = a.len() / dim;
    let band =
        (n.max(b.len() / dim) as f64 * crate::offline::analysis::DTW_BAND_SHARE).ceil() as usize;
    let demean = |s: &[f64]| -> Vec<f64> {
        let frames = (s.len() / dim).max(1) as f64;
        let mut mean = vec![0.0; dim];
        for row in s.chunks_exact(dim) {
            for (acc, v) in mean.iter_mut().zip(row) {
                *acc += v / frames;
            }
        }
        s.iter()
            .enumerate()
            .map(|(i, v)| v - mean[i % dim])
            .collect()
    };
    let alignment = ica_core::dtw::align(&demean(&a), &demean(&b), dim, Some(band))?;
    let map = ica_core::dtw::warp_map(&alignment.path, n);
    Ok(ks
        .iter()
        .map(|&k| {
            let values = other.component(k);
            map.iter()
                .map(|&j| {
                    let lo = j.floor() as usize;
                    let hi = (lo + 1).min(values.len() - 1);
                    let t = j - lo as f64;
                    values[lo] * (1.0 - t) + values[hi] * t
                })
                .collect()
        })
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
    args: &EditArgs,
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
    for kv in &args.translate {
        plan.offsets[check_component(model, kv, "--translate")?] += kv.value as f32;
    }
    for kv in &args.gain {
        plan.gains[check_component(model, kv, "--gain")?] *= kv.value as f32;
    }
    if let Some(text) = &args.to_emotion {
        let space = emotion_components(model, &args.model)?;
        let (name, point) = target_point(model, text)?;
        if !(0.0..=1.0).contains(&args.amount) {
            return Err(UsageError(format!("--amount {} is outside 0..1", args.amount)).into());
        }
        match args.lowpass {
            // The live daemon's edit: towards the point from a causal low-pass of each emotion
            // component, exactly as `serve` does with a zero ramp.
            Some(window) => {
                let mut state = EditState::for_model(model, window as f32);
                state.set_ramp(0.0);
                let p: Vec<f32> = point.iter().map(|&v| v as f32).collect();
                state.set_target(&name, &p)?;
                state.set_amount(args.amount as f32)?;
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
                    plan.offsets[k] += (args.amount as f32) * (t - c);
                }
            }
        }
    }
    if let Some(other) = &args.replace_emotion_from {
        // The emotion axes take the other take's series (the paper's Copy & Replace); the
        // other emotion components also follow what is said, so they only take the other
        // take's level: their own motion stays.
        let space = emotion_components(model, &args.model)?;
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
    if let Some(other) = &args.add_emotion_from {
        let Some(path) = &args.other_model else {
            return Err(UsageError("--add-emotion-from needs --other-model m2.json".into()).into());
        };
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

pub(crate) fn run(args: &EditArgs) -> Result<()> {
    let model = crate::offline::load_model(&args.model)?;
    let take = offline::load_take(&args.file)?;
    let map = offline::match_take(&model, &take, &args.file)?;
    let frames = offline::to_model_order(&take, &map);
    let projected = offline::project_take(&model, &frames)?;
    let mut plan = plan(args, &model, &projected, &frames)?;
    let mut frame_edit = FrameEdit::identity(model.components());
    for k in 0..plan.offsets.len() {
        frame_edit.set_offset(k, plan.offsets[k])?;
        frame_edit.set_gain(k, plan.gains[k])?;
    }
    let mut live = plan.live.take();
    let dt = (1.0 / model.rate_hz()) as f32;
    let mut edited = offline::resynthesise(&model, &projected, |f, u| {
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
    let out = assemble(&take, model.labels(), &map, &frames, edited, args.keep_gaps)?;
    replay::save(&args.out, &out).with_context(|| format!("{}", args.out.display()))?;
    crate::out!("edited {} frames -> {}", out.n_frames(), args.out.display());
    Ok(())
}

/// The output take: the model's markers edited (gaps filled from the model unless `keep_gaps`),
/// followed by the take's extra markers unchanged, so nothing the user gave is lost.
fn assemble(
    take: &Take,
    model_labels: &[String],
    map: &crate::engine::layout::LabelMap,
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
