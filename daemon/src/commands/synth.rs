//! `emoshift synth`: write a paired synthetic session.

use anyhow::{Context, Result};
use replay::synth::{write_session, Layout, SynthParams};

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
        rate_hz: args.rate,
        head_motion: args.head_motion,
        layout: Layout {
            markers: args.markers,
            naming: args.names,
            rigid: args.rigid,
            placement_jitter_mm: args.placement_jitter,
        },
    };
    params.validate().map_err(|e| UsageError(e.to_string()))?;
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
    crate::out!("manifest: {}", summary.manifest.display());
    Ok(())
}
