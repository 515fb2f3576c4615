//! `emoshift analyze --model m.json --manifest session.toml [--regions r.toml] --out DIR
//! [--write-model]`.

use anyhow::{Context, Result};

use crate::cli::AnalyzeArgs;
use crate::offline;
use crate::offline::analysis::{self, Inputs};

pub(crate) fn run(args: &AnalyzeArgs) -> Result<()> {
    let mut model = crate::offline::load_model(&args.model)?;
    let session = offline::load_session(&args.manifest)?;
    let regions_path = match &args.regions {
        Some(p) => p.clone(),
        None => session.base_dir.join("regions.toml"),
    };
    let regions = analysis::resolve_regions(&regions_path, &model)?;
    let takes = analysis::project_session(&model, &session)?;
    let inputs = Inputs {
        model: &model,
        model_path: &args.model,
        manifest_path: &args.manifest,
        regions_path: &regions_path,
    };
    let report = analysis::analyze(&inputs, &takes, &regions)?;
    let written = analysis::write_report(&args.out, &report, &takes)?;
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
    for (name, level) in &report.levels {
        crate::out!("level {name}: {level:.4}");
    }
    if args.write_model {
        analysis::write_into_model(&mut model, &report)?;
        let file = std::fs::File::create(&args.model)
            .with_context(|| format!("cannot write {}", args.model.display()))?;
        model.save(std::io::BufWriter::new(file))?;
        crate::out!("roles and levels written to {}", args.model.display());
    }
    for p in written {
        crate::out!("wrote {}", p.display());
    }
    Ok(())
}
