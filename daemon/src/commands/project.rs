//! `emoshift project --model m.json FILE --out components.csv`, streamed from the take file to
//! the CSV in blocks ([`crate::offline::streamed::project_file`]).

use anyhow::Result;

use crate::cli::ProjectArgs;
use crate::offline;

pub(crate) fn run(args: &ProjectArgs) -> Result<()> {
    offline::output::check_out(&args.out, &[&args.file, &args.model], args.force)?;
    offline::output::check_out_format(&args.out, "csv")?;
    let model = offline::load_model(&args.model)?;
    let mut progress = super::progress::for_stderr("project");
    let input = (args.file.as_path(), offline::takes::input_limit());
    let done = offline::streamed::project_file(
        &model,
        input,
        &args.out,
        args.block_frames,
        progress.as_mut(),
    );
    let s = super::progress::settle(progress.as_mut(), done)?;
    for notice in &s.notices {
        crate::out!("warning: {} {notice}", args.file.display());
    }
    crate::out!(
        "projected {} frames onto {} ({} with missing markers, {} held) -> {}",
        s.frames,
        super::count(s.components, "component"),
        s.masked,
        s.held,
        args.out.display()
    );
    Ok(())
}
