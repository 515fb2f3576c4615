//! `emoshift convert IN OUT [--start F|Ts] [--end F|Ts]`: read any supported format, write any
//! other, optionally only a frame or time range; gaps are kept.

use anyhow::{Context, Result};

use crate::cli::ConvertArgs;

pub(crate) fn run(args: &ConvertArgs) -> Result<()> {
    crate::offline::output::check_out(&args.output, &[&args.input], args.force)?;
    let cut_off = crate::offline::takes::cut_off(&args.input);
    let mut take = crate::offline::load_take(&args.input)?;
    if args.range.is_some() {
        let (start, end) = (args.range.start, args.range.end);
        let range = crate::offline::trim::frame_range(&take, start, end)
            .with_context(|| format!("{}", args.input.display()))?;
        take.keep_frames(range);
    }
    if let Some(note) = cut_off {
        crate::out!("warning: {} {note}", args.input.display());
    }
    replay::save(&args.output, &take).with_context(|| format!("{}", args.output.display()))?;
    let gaps: usize = take.missing.iter().filter(|&&m| m).count();
    if let Some(note) = crate::offline::takes::analog_left_out(&args.input) {
        crate::out!("warning: {} {note}", args.input.display());
    }
    crate::out!(
        "wrote {}: {} markers, {} frames at {} Hz, {} missing samples",
        args.output.display(),
        take.n_markers(),
        take.n_frames(),
        take.rate_hz,
        gaps
    );
    Ok(())
}
