//! `emoshift analyze --model m.json --manifest session.toml [--regions r.toml] --out DIR
//! [--write-model]`.

use std::path::Path;

use anyhow::{bail, Context, Result};
use ica_core::model::IcaModel;

use crate::cli::AnalyzeArgs;
use crate::offline;
use crate::offline::analysis::{self, Inputs};

pub(crate) fn run(args: &AnalyzeArgs) -> Result<()> {
    offline::output::check_out_dir(&args.out, args.force)?;
    let to = Report {
        dir: &args.out,
        write_model: args.write_model,
        axes: args.axes,
    };
    analyze_and_write(&args.model, &args.manifest, args.regions.as_deref(), &to).map(drop)
}

/// The fitted space's axes, tests, points and conditioning, when the session shows one.
fn print_fitted(report: &analysis::Report, m: usize) -> Result<()> {
    let Some(space) = &report.space else {
        return Ok(());
    };
    let Some(basis) = &space.basis else {
        return Ok(());
    };
    let tests: Vec<String> = basis
        .tests
        .iter()
        .map(|t| {
            let kept = if t.kept { "" } else { " (not kept)" };
            format!("F {}{kept}", analysis::space::f_text(t.f))
        })
        .collect();
    crate::out!(
        "space: {} axes fitted over all {m} components ({}; offsets from {})",
        basis.axes.len(),
        tests.join(", "),
        if basis.aligned {
            "aligned pairs"
        } else {
            "take means"
        }
    );
    let names: Vec<String> = (1..=basis.axes.len()).map(|j| format!("e{j}")).collect();
    for (name, point) in &basis.points {
        crate::out!(
            "  point {name}: {}",
            super::inspect::point_text(&names, &point.level)
        );
    }
    if let Some(c) = &space.conditioning {
        crate::out!("conditioning: {}", c.note);
    }
    Ok(())
}

/// Where [`analyze_and_write`] puts its results.
pub(crate) struct Report<'a> {
    /// The report's folder.
    pub dir: &'a Path,
    /// Roles and emotion levels go into the model file too.
    pub write_model: bool,
    /// The axes of the emotion space the model gets.
    pub axes: analysis::Axes,
}

/// Analyses the model at `model_path` on the session at `manifest`, writes the report and
/// prints the table, as `analyze` does; returns the model (with roles and levels when
/// written back) and the report.
pub(crate) fn analyze_and_write(
    model_path: &Path,
    manifest: &Path,
    regions: Option<&Path>,
    to: &Report<'_>,
) -> Result<(IcaModel, analysis::Report)> {
    let mut model = crate::offline::load_model(model_path)?;
    let session = offline::load_session(manifest)?;
    let regions_path = match regions {
        Some(p) => p.to_path_buf(),
        None => session.base_dir.join("regions.toml"),
    };
    if !regions_path.exists() {
        bail!(
            "analyze needs a regions file naming the mouth, eyebrows and eyelids markers, and \
             {} does not exist; propose one with `emoshift regions TAKE --out {}`, check it, \
             and run again",
            regions_path.display(),
            regions_path.display()
        );
    }
    let regions = analysis::resolve_regions(&regions_path, &model)?;
    let inputs = Inputs {
        model: &model,
        model_path,
        manifest_path: manifest,
        regions_path: &regions_path,
    };
    let mut progress = super::progress::for_stderr("analyze");
    let done = analysis::analyze_session(&inputs, &session, &regions, progress.as_mut());
    let (report, timeline) = super::progress::settle(progress.as_mut(), done)?;
    let written = analysis::write_report(to.dir, &report, &timeline)?;
    print_table(&report)?;
    print_fitted(&report, model.components())?;
    if to.write_model {
        analysis::write_into_model(&mut model, &report, to.axes)?;
        let file = std::fs::File::create(model_path)
            .with_context(|| format!("cannot write {}", model_path.display()))?;
        model.save(std::io::BufWriter::new(file))?;
        crate::out!("roles and levels written to {}", model_path.display());
    }
    for p in written {
        crate::out!("wrote {}", p.display());
    }
    Ok((model, report))
}

/// The components' metrics, the emotion note and the levels, as `analyze` prints them.
fn print_table(report: &analysis::Report) -> Result<()> {
    for c in &report.components {
        crate::out!(
            "c{:<2} {:<9} d_emotion {:>8} d_level {:>8} d_mouth {:>8.4} d_eyebrows {:>8.4} d_eyelids {:>8.4}",
            c.index,
            format!("{:?}", c.role).to_lowercase(),
            c.d_emotion.map_or("-".into(), |d| format!("{d:.4}")),
            c.d_level.map_or("-".into(), |d| format!("{d:.4}")),
            c.d_region["mouth"],
            c.d_region["eyebrows"],
            c.d_region["eyelids"]
        );
    }
    if !report.emotion_note.is_empty() {
        crate::out!("note: {}", report.emotion_note);
    }
    for line in &report.advice {
        crate::out!("warning: {line}");
    }
    match &report.space {
        Some(space) if space.components.len() > 1 => {
            for (name, point) in &space.points {
                let names: Vec<String> = space.components.iter().map(|k| format!("c{k}")).collect();
                let text = super::inspect::point_text(&names, &point.level);
                crate::out!("level {name}: {text}");
            }
        }
        _ => {
            for (name, level) in &report.levels {
                crate::out!("level {name}: {level:.4}");
            }
        }
    }
    Ok(())
}
