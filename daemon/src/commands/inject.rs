//! `emoshift inject FILE... --out DIR`: real captures cut into a paired session with a known
//! signal ([`crate::offline::inject`]).

use anyhow::{Context, Result};
use replay::session::{Regions, REGIONS_FILE};

use crate::cli::InjectArgs;
use crate::exit::UsageError;
use crate::offline::inject::{write_session, InjectParams, InjectedSession, TRUTH_FILE};
use crate::offline::training::{self, PrepOptions, DEFAULT_HEAD_PATTERNS};
use crate::offline::{self, LoadedTake};

pub(crate) fn run(args: &InjectArgs) -> Result<()> {
    let format = replay::Format::from_name(&args.format).ok_or_else(|| {
        UsageError(format!(
            "unknown format {:?} (expected c3d, trc or csv)",
            args.format
        ))
    })?;
    offline::output::check_out_dir(&args.out, args.force)?;
    let regions = args
        .regions
        .as_deref()
        .map(Regions::load)
        .transpose()
        .map_err(anyhow::Error::from)?;
    let takes = load_takes(args)?;
    let head = head_reference(args, regions.as_ref(), &takes)?;
    let params = InjectParams {
        seed: args.seed,
        levels: args.levels,
        field_mm: args.field_mm,
        sentence_s: args.sentence_s,
        jitter_s: args.jitter_s,
        pace_spread: args.pace_spread,
    };
    let captures = takes
        .into_iter()
        .map(|t| (t.path.display().to_string(), t.take))
        .collect();
    let session = InjectedSession::build(captures, &head, &params)
        .map_err(|e| UsageError(format!("{e:#}")))?;
    let manifest = write_session(&args.out, &session, format)
        .with_context(|| format!("cannot write the session to {}", args.out.display()))?;
    if let Some(regions) = &regions {
        let path = args.out.join(REGIONS_FILE);
        std::fs::write(&path, regions.to_toml()?)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    print_written(args, &session, &head, &manifest)
}

/// The captures named on the command line, read.
fn load_takes(args: &InjectArgs) -> Result<Vec<LoadedTake>> {
    args.files
        .iter()
        .map(|path| {
            Ok(LoadedTake {
                path: path.clone(),
                take: offline::load_take(path)?,
            })
        })
        .collect()
}

/// What `inject` wrote and where, as it prints it.
fn print_written(
    args: &InjectArgs,
    session: &InjectedSession,
    head: &[String],
    manifest: &std::path::Path,
) -> Result<()> {
    let sentences = session.cuts().len() / args.levels;
    crate::out!(
        "wrote {} takes: {sentences} sentences x {} levels ({}) of a {} mm field to {}",
        session.cuts().len(),
        args.levels,
        session.level_names().join(", "),
        args.field_mm,
        args.out.display()
    );
    crate::out!(
        "field in {}",
        if head.is_empty() {
            "world coordinates (no head reference)".to_string()
        } else {
            format!("the frame of {}", head.join(", "))
        }
    );
    crate::out!("truth: {}", args.out.join(TRUTH_FILE).display());
    crate::out!("manifest: {}", manifest.display());
    Ok(())
}

/// The head reference as `train` would choose it with the same flag and regions file
/// (labels and globs resolved against the captures).
fn head_reference(
    args: &InjectArgs,
    regions: Option<&Regions>,
    takes: &[LoadedTake],
) -> Result<Vec<String>> {
    if args.head_reference.as_deref() == Some("none") {
        return Ok(Vec::new());
    }
    let patterns = DEFAULT_HEAD_PATTERNS.map(String::from);
    let choice = super::train::head_choice(args.head_reference.as_deref(), &patterns, regions);
    let options = PrepOptions {
        head: choice,
        ..PrepOptions::default()
    };
    let data = training::prepare(takes, &options).context("cannot find the head reference")?;
    Ok(data.reference)
}
