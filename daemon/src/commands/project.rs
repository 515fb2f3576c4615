//! `emoshift project --model m.json FILE --out components.csv`.

use std::io::Write;

use anyhow::{Context, Result};

use crate::cli::ProjectArgs;
use crate::offline;

pub(crate) fn run(args: &ProjectArgs) -> Result<()> {
    offline::output::check_out(&args.out, &[&args.file, &args.model], args.force)?;
    let model = crate::offline::load_model(&args.model)?;
    let take = offline::load_take(&args.file)?;
    let map = offline::match_take(&model, &take, &args.file)?;
    let frames = offline::to_model_order(&take, &map);
    let projected = offline::project_take(&model, &frames)?;
    let file = std::fs::File::create(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let mut out = std::io::BufWriter::new(file);
    write!(out, "frame,time")?;
    for k in 0..projected.m {
        write!(out, ",c{k}")?;
    }
    writeln!(out)?;
    for (f, row) in projected.u.chunks_exact(projected.m).enumerate() {
        write!(
            out,
            "{},{:.6}",
            take.first_frame + f as i64,
            take.time_of(f)
        )?;
        for v in row {
            write!(out, ",{v}")?;
        }
        writeln!(out)?;
    }
    out.flush()
        .with_context(|| format!("cannot write {}", args.out.display()))?;
    let masked = projected.status.iter().filter(|s| s.masked).count();
    let held = projected.status.iter().filter(|s| s.held).count();
    crate::out!(
        "projected {} frames onto {} components ({} with missing markers, {} held) -> {}",
        take.n_frames(),
        projected.m,
        masked,
        held,
        args.out.display()
    );
    Ok(())
}
