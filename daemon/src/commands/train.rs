//! `emoshift train`: learn an ICA model from takes.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use ica_core::fit::FastIcaParams;
use ica_core::model::IcaModel;
use ica_core::whiten::DEFAULT_VARIANCE_TARGET;
use indicatif::ProgressBar;

use crate::cli::TrainArgs;
use crate::exit::UsageError;
use crate::offline::training::{
    self, HeadChoice, PrepOptions, PrepReport, SpeedLimit, Stage, StreamOptions, TrainOptions,
    Trained,
};
use crate::offline::{self, LoadedTake};
use replay::session::Regions;

/// The regions file's region naming the rigid head markers.
pub const HEAD_REGION: &str = "head_reference";

/// The regions file: `--regions`, else `regions.toml` beside the manifest if there is one.
fn regions(args: &TrainArgs) -> Result<Option<Regions>> {
    let path = args.regions.clone().or_else(|| {
        let p = args.manifest.as_ref()?.parent()?.join("regions.toml");
        p.exists().then_some(p)
    });
    // Its errors name the file already.
    path.map(|path| Regions::load(&path).map_err(anyhow::Error::from))
        .transpose()
}

/// The head reference: `--head-reference`, else the regions file's `head_reference`, else
/// auto with `patterns`.
pub(crate) fn head_choice(
    head_reference: Option<&str>,
    patterns: &[String],
    regions: Option<&Regions>,
) -> HeadChoice {
    let auto = HeadChoice::Auto {
        patterns: patterns.to_vec(),
    };
    if let Some(text) = head_reference {
        return match text {
            "none" => HeadChoice::None,
            "auto" => auto,
            list => HeadChoice::Labels {
                patterns: list.split(',').map(|s| s.trim().to_string()).collect(),
                requested: true,
            },
        };
    }
    match regions.and_then(|r| r.regions.get(HEAD_REGION)) {
        Some(patterns) => HeadChoice::Labels {
            patterns: patterns.clone(),
            requested: false,
        },
        None => auto,
    }
}

fn speed_limit(text: &str) -> Result<SpeedLimit> {
    Ok(match text {
        "auto" => SpeedLimit::Auto,
        "off" => SpeedLimit::Off,
        v => match v.parse::<f64>() {
            Ok(x) if x.is_finite() && x > 0.0 => SpeedLimit::MmPerS(x),
            _ => {
                return Err(UsageError(format!(
                    "--max-speed {v:?}: expected auto, off or a speed in mm/s"
                ))
                .into())
            }
        },
    })
}

fn params(args: &TrainArgs) -> Result<FastIcaParams> {
    let mut params = FastIcaParams::default()
        .seed(args.seed)
        .restarts(args.restarts)
        .max_iter(args.max_iter)
        .tol(args.tol);
    params = match (args.components, args.variance) {
        (Some(_), Some(_)) => {
            return Err(UsageError("give --variance or --components, not both".into()).into())
        }
        (Some(m), None) => params.n_components(m),
        (None, Some(v)) => params.variance_target(v),
        (None, None) => params,
    };
    params.check().map_err(|e| UsageError(e.to_string()))?;
    Ok(params)
}

/// The training options a command line asks for.
pub(crate) fn options(args: &TrainArgs) -> Result<TrainOptions> {
    let regions = regions(args)?;
    Ok(TrainOptions {
        prep: PrepOptions {
            rate_hz: args.rate,
            max_missing_share: args.max_missing,
            speed: speed_limit(&args.max_speed)?,
            head: head_choice(
                args.head_reference.as_deref(),
                &args.head_patterns,
                regions.as_ref(),
            ),
            bounds: !args.no_bounds,
        },
        params: params(args)?,
        noise_floor: args.components.is_none() && args.variance.is_none(),
        regions,
    })
}

/// The default options with a regions file (which may name the head reference).
fn options_with_regions(regions: Regions) -> TrainOptions {
    let mut options = TrainOptions::default();
    let patterns = offline::training::DEFAULT_HEAD_PATTERNS.map(String::from);
    options.prep.head = head_choice(None, &patterns, Some(&regions));
    options.regions = Some(regions);
    options
}

pub(crate) fn run(args: &TrainArgs) -> Result<()> {
    let mut options = options(args)?;
    if let (None, Some(manifest)) = (args.rate, args.manifest.as_deref()) {
        // A manifest declares its session's rate: the model's, unless --rate says otherwise.
        options.prep.rate_hz = Some(offline::load_session(manifest)?.rate_hz);
    }
    let takes = offline::take_inputs(args.manifest.as_deref(), &args.files)?;
    let mut inputs: Vec<&Path> = takes.iter().map(|t| t.path.as_path()).collect();
    inputs.extend(args.manifest.as_deref());
    offline::output::check_out(&args.out, &inputs, args.force)?;
    offline::output::check_out_format(&args.out, "json")?;
    let stream = StreamOptions {
        threads: args.threads,
        always_stream: args.stream,
        hold_frames: None,
    };
    let started = Instant::now();
    let mut progress = super::progress::for_stderr("train");
    let trained = training::train_files(&takes, &options, &stream, progress.as_mut());
    let trained = super::progress::settle(progress.as_mut(), trained)?;
    save_and_print(trained, takes.len(), &args.out, started).map(drop)
}

/// Trains on the takes of the session at `manifest`, at its rate, with the default options and
/// `regions` (the head reference it may name), writes the model to `out` and prints what
/// training found, as `train --manifest` does; returns the model.
///
/// # Errors
/// An unreadable manifest, regions file or take, or training failed.
pub(crate) fn train_session(
    manifest: &Path,
    regions: Option<&Path>,
    out: &Path,
) -> Result<IcaModel> {
    let mut options = match regions {
        Some(path) => options_with_regions(Regions::load(path)?),
        None => TrainOptions::default(),
    };
    options.prep.rate_hz = Some(offline::load_session(manifest)?.rate_hz);
    let takes = offline::load_inputs(Some(manifest), &[])?;
    train_and_save(&takes, &options, out)
}

/// Trains on `takes` held in memory, writes the model to `out` and prints what training
/// found, as `train` does; returns the model.
fn train_and_save(takes: &[LoadedTake], options: &TrainOptions, out: &Path) -> Result<IcaModel> {
    let started = Instant::now();
    let bar = ProgressBar::new_spinner();
    let trained = training::train(takes, options, &mut |stage| match stage {
        Stage::Preparing => bar.set_message(format!("preparing {} takes", takes.len())),
        Stage::Fitting { restarts } => {
            bar.set_message(format!("whitening and FastICA ({restarts} restarts)"));
            bar.enable_steady_tick(std::time::Duration::from_millis(120));
        }
    })?;
    bar.finish_and_clear();
    save_and_print(trained, takes.len(), out, started)
}

/// Writes the model to `out` and prints what training found.
fn save_and_print(
    trained: Trained,
    takes: usize,
    out: &Path,
    started: Instant,
) -> Result<IcaModel> {
    let Trained {
        model,
        data,
        gaps,
        noise_mm,
        capped_at_noise,
    } = trained;
    let file =
        std::fs::File::create(out).with_context(|| format!("cannot create {}", out.display()))?;
    model
        .save(std::io::BufWriter::new(file))
        .with_context(|| format!("cannot write {}", out.display()))?;
    print_preparation(&data)?;
    if gaps.frames > 0 || gaps.frames_left_out > 0 {
        crate::out!(
            "gaps: {} marker samples in {} frames filled from the visible markers (PCA, EM); {} frames missing more than half their markers left out",
            // Counted per coordinate; a marker's gap is its three.
            gaps.samples / 3,
            gaps.frames,
            gaps.frames_left_out
        );
    }
    print_summary(&model, takes, started.elapsed().as_secs_f64())?;
    if capped_at_noise {
        crate::out!(
            "the default {:.0} % of the variance would reach into noise ({noise_mm:.3} mm per coordinate): kept the {} above the noise floor",
            100.0 * DEFAULT_VARIANCE_TARGET,
            super::count(model.components(), "component")
        );
    }
    super::inspect::print_quality(model.quality())?;
    crate::out!("model: {}", out.display());
    Ok(model)
}

fn print_preparation(data: &PrepReport) -> Result<()> {
    for note in data.label_notes.iter().take(5) {
        crate::out!("warning: {note}");
    }
    if data.label_notes.len() > 5 {
        crate::out!(
            "warning: and {} more takes whose markers differ from the first take's",
            data.label_notes.len() - 5
        );
    }
    for (file, from, to) in &data.resampled {
        crate::out!("resampled {file} from {from} Hz to {to} Hz");
    }
    for (label, share) in &data.excluded {
        crate::out!(
            "excluded marker {label}: missing in {:.1} % of the frames",
            100.0 * share
        );
    }
    crate::out!("{}", glitch_line(data));
    crate::out!(
        "head reference ({}): {}",
        data.head.source,
        data.head.verdict
    );
    if let Some((median, p95)) = data.residual_summary {
        crate::out!(
            "head stabilised on {}: residual median {median:.2} mm, p95 {p95:.2} mm",
            data.reference.join(", ")
        );
    }
    Ok(())
}

/// How many samples were glitches, by what rule, and the markers with the most.
fn glitch_line(data: &PrepReport) -> String {
    let limit = match data.capture.max_speed_mm_s {
        Some(v) => format!("faster than {v:.0} mm/s"),
        None => "no speed limit".into(),
    };
    let bounds = if data.capture.bounds.is_some() {
        " or outside their marker's learned region"
    } else {
        ""
    };
    let mut worst: Vec<(usize, &String)> = data
        .glitches_per_marker
        .iter()
        .copied()
        .zip(&data.labels)
        .filter(|(c, _)| *c > 0)
        .collect();
    worst.sort_by_key(|w| std::cmp::Reverse(w.0));
    let names: Vec<String> = worst
        .iter()
        .take(5)
        .map(|(c, l)| format!("{l} {c}"))
        .collect();
    let detail = if names.is_empty() {
        String::new()
    } else {
        format!(" ({})", names.join(", "))
    };
    format!(
        "glitches: {} samples {limit}{bounds} treated as missing{detail}",
        data.glitches
    )
}

fn print_summary(model: &IcaModel, takes: usize, seconds: f64) -> Result<()> {
    let r = model.report();
    let best = &r.restarts[r.best_restart];
    crate::out!(
        "trained on {}: used {} of {} frames, {} markers, {} dead channels",
        super::count(takes, "take"),
        r.frames_used,
        r.frames_total,
        model.markers(),
        r.dead_channels.len()
    );
    crate::out!(
        "components: {} keeping {:.2} % of the variance",
        r.components,
        100.0 * r.variance_kept
    );
    for (i, run) in r.restarts.iter().enumerate() {
        let on = if run.frames > 0 && run.frames < r.frames_used {
            format!(" on {} frames", run.frames)
        } else {
            String::new()
        };
        crate::out!(
            "  restart {i}{on}: {} iterations, {}, negentropy {:.5}{}",
            run.iterations,
            if run.converged {
                "converged"
            } else {
                "NOT converged"
            },
            run.negentropy,
            if i == r.best_restart { "  <- kept" } else { "" }
        );
        if let Some(refine) = &run.refinement {
            crate::out!(
                "    refined on all {} frames: {} iterations, {}",
                refine.frames,
                refine.iterations,
                if refine.converged {
                    "converged"
                } else {
                    "NOT converged"
                }
            );
        }
    }
    crate::out!(
        "kept restart {} ({}), {seconds:.2} s",
        r.best_restart,
        if best.solution_converged() {
            "converged"
        } else {
            "not converged: raise --max-iter"
        }
    );
    Ok(())
}
