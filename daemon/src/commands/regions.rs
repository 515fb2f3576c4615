//! `emoshift regions TAKE --out regions.toml`: a first regions file from a take's names and
//! geometry ([`crate::offline::regions`]).

use anyhow::{Context, Result};

use crate::cli::RegionsArgs;
use crate::offline::regions;

pub(crate) fn run(args: &RegionsArgs) -> Result<()> {
    crate::offline::output::check_out(&args.out, &[&args.take], args.force)?;
    let take = crate::offline::load_take(&args.take)?;
    let proposed = regions::propose(&take);
    let text = regions::to_toml(&proposed, &args.take.display().to_string());
    std::fs::write(&args.out, text)
        .with_context(|| format!("cannot write {}", args.out.display()))?;
    for (label, share) in &proposed.left_out {
        crate::out!("left out {label}: {}", regions::why_left_out(*share));
    }
    for region in ["mouth", "eyebrows", "eyelids", "head_reference"] {
        let n = proposed
            .markers
            .iter()
            .filter(|p| p.region == region)
            .count();
        crate::out!("{region}: {n} markers");
    }
    crate::out!(
        "wrote {}: check each line (a comment says why), then emoshift analyze --regions {}",
        args.out.display(),
        args.out.display()
    );
    Ok(())
}
