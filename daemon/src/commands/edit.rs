//! `emoshift edit --model m.json FILE --out OUT [--translate k=a]... [--gain k=g]...`.

use anyhow::{bail, Context, Result};
use ica_core::model::IcaModel;
use replay::Take;

use crate::cli::{EditArgs, KeyValue};
use crate::exit::UsageError;
use crate::offline::{self, ModelFrames};

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

pub(crate) fn run(args: &EditArgs) -> Result<()> {
    let model = super::load_model(&args.model)?;
    let take = offline::load_take(&args.file)?;
    let map = offline::match_take(&model, &take, &args.file)?;
    let frames = offline::to_model_order(&take, &map);
    let projected = offline::project_take(&model, &frames)?;
    let mut offsets = vec![0.0f32; model.components()];
    let mut gains = vec![1.0f32; model.components()];
    for kv in &args.translate {
        offsets[check_component(&model, kv, "--translate")?] += kv.value as f32;
    }
    for kv in &args.gain {
        gains[check_component(&model, kv, "--gain")?] *= kv.value as f32;
    }
    let edited = offline::resynthesise(&model, &projected, |_, edit| {
        for k in 0..offsets.len() {
            // Values were checked above; a failure here is an internal invariant.
            let _ = edit.set_offset(k, offsets[k]);
            let _ = edit.set_gain(k, gains[k]);
        }
    })?;
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
    map: &crate::layout::LabelMap,
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
