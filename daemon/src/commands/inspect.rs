//! `emoshift inspect model.json [--json]`.

use anyhow::Result;
use ica_core::quality::ModelQuality;

use crate::cli::InspectArgs;

pub(crate) fn run(args: &InspectArgs) -> Result<()> {
    let model = crate::offline::load_model(&args.model)?;
    if args.json {
        model.save(std::io::stdout().lock())?;
        crate::out!();
        return Ok(());
    }
    let r = model.report();
    crate::out!("model:      {}", args.model.display());
    crate::out!(
        "markers:    {} ({} channels)",
        model.markers(),
        model.channels()
    );
    crate::out!("rate:       {} Hz", model.rate_hz());
    crate::out!(
        "components: {} keeping {:.2} % of the variance",
        model.components(),
        100.0 * model.variance_kept()
    );
    crate::out!(
        "training:   {} of {} frames, {} {} restarts, kept {}",
        r.frames_used,
        r.frames_total,
        r.restarts.len(),
        r.algorithm,
        r.best_restart
    );
    print_emotion(&model)?;
    crate::out!("roles:");
    for (k, role) in model.roles().iter().enumerate() {
        let norm = model.mixing().column(k).norm();
        crate::out!("  c{k}: {role:?} (mixing norm {norm:.3} mm)");
    }
    if model.quality().is_empty() {
        crate::out!("quality:    not recorded (trained before quality reports)");
        return Ok(());
    }
    print_quality(model.quality())
}

/// The model's emotion space: its axes or components and each emotion's point.
fn print_emotion(model: &ica_core::model::IcaModel) -> Result<()> {
    let emotion = model.emotion();
    let space = emotion.space_components();
    let list: Vec<String> = space.iter().map(|c| format!("c{c}")).collect();
    match emotion.component {
        _ if !emotion.axes.is_empty() => crate::out!(
            "emotion:    {} axes fitted over all {} components (emotion components {})",
            emotion.dims(),
            model.components(),
            if list.is_empty() {
                "none".to_string()
            } else {
                list.join(", ")
            }
        ),
        Some(k) if space.len() > 1 => {
            crate::out!("emotion:    components {} (main c{k})", list.join(", "));
        }
        Some(k) => crate::out!("emotion:    component {k}"),
        None if emotion.dims() > 0 => crate::out!("emotion:    components {}", list.join(", ")),
        None => crate::out!("emotion:    not analysed (run `emoshift analyze --write-model`)"),
    }
    let names = emotion.axis_names();
    for name in emotion.names() {
        if let Some(point) = emotion.point(&name) {
            crate::out!("  level {name}: {}", point_text(&names, &point));
        }
    }
    if let Some(c) = &emotion.conditioning {
        crate::out!("  conditioning: {}", c.note);
    }
    Ok(())
}

/// An emotion's point: its level on the one axis, or `c0 0.1234, c2 -0.5678` over several
/// (`axes` names them: `c0`, `e1`, ...).
pub(crate) fn point_text(axes: &[String], point: &[f64]) -> String {
    match point {
        [level] => format!("{level:.4}"),
        _ => axes
            .iter()
            .zip(point)
            .map(|(k, v)| format!("{k} {v:.4}"))
            .collect::<Vec<_>>()
            .join(", "),
    }
}

/// Prints a model's quality report: the head decision, stability, residuals and warnings.
pub(crate) fn print_quality(q: &ModelQuality) -> Result<()> {
    if let Some(h) = &q.head {
        crate::out!("head:       {}: {}", h.source, h.verdict);
        let numbers: Vec<String> = [
            ("noise", h.noise_mm, 3),
            ("deformation", h.deformation_mm, 2),
            ("head motion", h.motion_mm, 2),
            ("pose error", h.pose_error_mm, 2),
        ]
        .iter()
        .filter_map(|(name, v, digits)| v.map(|v| format!("{name} {v:.digits$} mm")))
        .chain(h.leakage.map(|l| format!("leakage {:.0} %", 100.0 * l)))
        .collect();
        if !numbers.is_empty() {
            crate::out!("  {}", numbers.join(", "));
        }
        if !h.residual_mm.is_empty() {
            let per: Vec<String> = h
                .residual_mm
                .iter()
                .map(|(l, r)| format!("{l} {r:.2}"))
                .collect();
            crate::out!("  reference residual (mm RMS): {}", per.join(", "));
        }
    }
    if !q.stability.is_empty() {
        let s: Vec<String> = q
            .stability
            .iter()
            .enumerate()
            .map(|(i, s)| format!("c{i} {s:.2}"))
            .collect();
        crate::out!(
            "stability:  {} (best-match |corr| across restarts)",
            s.join(", ")
        );
    }
    if !q.residual_by_region_mm.is_empty() {
        let r: Vec<String> = q
            .residual_by_region_mm
            .iter()
            .map(|(name, v)| format!("{name} {v:.2}"))
            .collect();
        crate::out!("residual:   {} (mm RMS per marker)", r.join(", "));
    }
    if let (Some(mm), Some(marker)) = (q.slow_residual_mm, &q.slow_residual_marker) {
        crate::out!("slow residual: {mm:.2} mm RMS, peak at {marker}");
    }
    if q.warnings.is_empty() {
        crate::out!("warnings:   none");
    } else {
        crate::out!("warnings:");
        for w in &q.warnings {
            crate::out!("  - {}", w.message);
        }
    }
    Ok(())
}
