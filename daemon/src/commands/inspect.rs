//! `emoshift inspect model.json [--json]`.

use anyhow::Result;

use crate::cli::InspectArgs;

pub(crate) fn run(args: &InspectArgs) -> Result<()> {
    let model = super::load_model(&args.model)?;
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
    let emotion = model.emotion();
    match emotion.component {
        Some(k) => crate::out!("emotion:    component {k}"),
        None => crate::out!("emotion:    not analysed (run `emoshift analyze --write-model`)"),
    }
    for (name, level) in &emotion.levels {
        crate::out!("  level {name}: {level:.4}");
    }
    crate::out!("roles:");
    for (k, role) in model.roles().iter().enumerate() {
        let norm = model.mixing().column(k).norm();
        crate::out!("  c{k}: {role:?} (mixing norm {norm:.3} mm)");
    }
    Ok(())
}
