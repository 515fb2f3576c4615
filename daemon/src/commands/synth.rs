//! `emoshift synth`: write a paired synthetic session.

use anyhow::{Context, Result};
use replay::synth::space::emotion_points;
use replay::synth::{write_session, Layout, SynthParams, Variation, DEFAULT_EMOTION_DIMS};

use crate::cli::SynthArgs;
use crate::exit::UsageError;

pub(crate) fn run(args: &SynthArgs) -> Result<()> {
    let format = replay::Format::from_name(&args.format).ok_or_else(|| {
        UsageError(format!(
            "unknown format {:?} (expected c3d, trc or csv)",
            args.format
        ))
    })?;
    if !(args.placement_jitter.is_finite() && (0.0..=20.0).contains(&args.placement_jitter)) {
        return Err(UsageError(format!(
            "--placement-jitter {}: expected 0 to 20 mm",
            args.placement_jitter
        ))
        .into());
    }
    let params = SynthParams {
        seed: args.seed,
        sentences: args.sentences,
        emotions: args.emotions.clone(),
        emotion_dims: args
            .emotion_dims
            .or_else(|| args.points.first().map(|p| p.point.len()))
            .unwrap_or(DEFAULT_EMOTION_DIMS),
        emotion_points: args.points.clone(),
        rate_hz: args.rate,
        head_motion: args.head_motion,
        layout: Layout {
            markers: args.markers,
            naming: args.names,
            rigid: args.rigid,
            placement_jitter_mm: args.placement_jitter,
        },
        variation: Variation {
            take_intensity: args.take_intensity,
            spread_effects: args.spread_effects,
            takes: args.takes.clone(),
            interaction: args.interaction,
            speech_rate: args.speech_rate.clone(),
        },
    };
    params.validate().map_err(|e| UsageError(e.to_string()))?;
    crate::offline::output::check_out_dir(&args.out, args.force)?;
    let summary = write_session(&args.out, &params, format)
        .with_context(|| format!("cannot write the session to {}", args.out.display()))?;
    crate::out!(
        "wrote {} takes ({} frames, {} markers at {} Hz; {}) to {}",
        summary.takes.len(),
        summary.total_frames,
        summary.markers,
        args.rate,
        params.layout.describe(),
        summary.dir.display()
    );
    crate::out!("emotion points: {}", describe_points(&params));
    if !params.variation.is_none() {
        crate::out!("variants: {}", params.variation.describe());
    }
    crate::out!("manifest: {}", summary.manifest.display());
    Ok(())
}

/// `neutral (0, 0), happy (1, 0), ...`: each emotion's point, as the truth records it.
fn describe_points(params: &SynthParams) -> String {
    let points = emotion_points(
        &params.emotions,
        params.emotion_dims,
        &params.emotion_points,
    );
    let described: Vec<String> = params
        .emotions
        .iter()
        .zip(points)
        .map(|(e, p)| {
            let coords: Vec<String> = p.iter().map(f64::to_string).collect();
            match coords.as_slice() {
                [one] => format!("{e} {one}"),
                _ => format!("{e} ({})", coords.join(", ")),
            }
        })
        .collect();
    described.join(", ")
}
