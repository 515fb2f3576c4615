//! `emoshift info FILE [--json]`: what a take holds.

use anyhow::Result;
use serde::Serialize;

use crate::cli::InfoArgs;

#[derive(Debug, Serialize)]
struct Info<'a> {
    file: String,
    markers: usize,
    frames: usize,
    rate_hz: f64,
    first_frame: i64,
    last_frame: i64,
    duration_s: f64,
    source_units: &'static str,
    missing_samples: usize,
    /// Analog samples per frame (C3D), which emoshift does not read.
    #[serde(skip_serializing_if = "Option::is_none")]
    analog_per_frame: Option<usize>,
    /// What is wrong with the file and what to do (a take cut off by a crash).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    warnings: Vec<String>,
    marker_list: Vec<MarkerInfo<'a>>,
}

#[derive(Debug, Serialize)]
struct MarkerInfo<'a> {
    label: &'a str,
    missing: usize,
}

pub(crate) fn run(args: &InfoArgs) -> Result<()> {
    let cut_off = crate::offline::takes::cut_off(&args.file);
    let take = match crate::offline::load_take(&args.file) {
        Ok(take) => take,
        // A take killed before its header counted a frame reads as none: say what it holds.
        Err(e) => {
            return Err(match cut_off {
                Some(note) => e.context(format!("{} {note}", args.file.display())),
                None => e,
            })
        }
    };
    let per_marker = take.missing_per_marker();
    let frames = take.n_frames();
    let info = Info {
        file: args.file.display().to_string(),
        markers: take.n_markers(),
        frames,
        rate_hz: take.rate_hz,
        first_frame: take.first_frame,
        last_frame: take.first_frame + frames as i64 - 1,
        duration_s: frames as f64 / take.rate_hz,
        source_units: take.source_units.as_str(),
        missing_samples: per_marker.iter().sum(),
        analog_per_frame: crate::offline::takes::analog_samples(&args.file),
        warnings: cut_off.into_iter().collect(),
        marker_list: take
            .labels
            .iter()
            .zip(&per_marker)
            .map(|(label, &missing)| MarkerInfo { label, missing })
            .collect(),
    };
    if args.json {
        crate::out!("{}", serde_json::to_string_pretty(&info)?);
    } else {
        print_text(&info)?;
    }
    Ok(())
}

fn print_text(info: &Info<'_>) -> Result<()> {
    crate::out!("file:     {}", info.file);
    crate::out!("markers:  {}", info.markers);
    crate::out!(
        "frames:   {} ({}..={}), {:.3} s",
        info.frames,
        info.first_frame,
        info.last_frame,
        info.duration_s
    );
    crate::out!("rate:     {} Hz", info.rate_hz);
    crate::out!("units:    {} (values shown in mm)", info.source_units);
    let total = info.frames * info.markers;
    let pct = if total == 0 {
        0.0
    } else {
        100.0 * info.missing_samples as f64 / total as f64
    };
    crate::out!("missing:  {} samples ({pct:.2} %)", info.missing_samples);
    if let Some(n) = info.analog_per_frame {
        crate::out!("analog:   {n} samples per frame (not read: emoshift reads the markers)");
    }
    for w in &info.warnings {
        crate::out!("warning:  {w}");
    }
    let width = info
        .marker_list
        .iter()
        .map(|m| m.label.len())
        .max()
        .unwrap_or(5)
        .max(5);
    crate::out!("  {:<width$}  missing", "label");
    for m in &info.marker_list {
        crate::out!("  {:<width$}  {}", m.label, m.missing);
    }
    Ok(())
}
