//! `emoshift train`: learn an ICA model from takes.

use std::time::Instant;

use anyhow::{bail, Context, Result};
use ica_core::fit::{FastIcaParams, FitData};
use ica_core::model::IcaModel;
use indicatif::{ProgressBar, ProgressStyle};

use crate::cli::TrainArgs;
use crate::exit::UsageError;
use crate::layout::LabelMap;
use crate::offline::{self, LoadedTake};

/// Frames of every take in the first take's marker order, with a per-channel missing mask.
struct TrainingData {
    labels: Vec<String>,
    rate_hz: f64,
    samples: Vec<f32>,
    missing: Vec<bool>,
}

fn gather(takes: &[LoadedTake]) -> Result<TrainingData> {
    let first = &takes[0];
    let labels = first.take.labels.clone();
    let rate_hz = first.take.rate_hz;
    let mut samples = Vec::new();
    let mut missing = Vec::new();
    for t in takes {
        if (t.take.rate_hz - rate_hz).abs() > 1e-6 * rate_hz {
            bail!(
                "{}: rate {} Hz differs from {} Hz of {}; train on takes of one rate",
                t.path.display(),
                t.take.rate_hz,
                rate_hz,
                first.path.display()
            );
        }
        let map = LabelMap::new(&labels, &t.take.labels)
            .with_context(|| format!("{}", t.path.display()))?;
        let frames = offline::to_model_order(&t.take, &map);
        samples.extend_from_slice(&frames.xyz);
        missing.extend(frames.missing.iter().flat_map(|&m| [m, m, m]));
    }
    Ok(TrainingData {
        labels,
        rate_hz,
        samples,
        missing,
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

pub(crate) fn run(args: &TrainArgs) -> Result<()> {
    let params = params(args)?;
    let started = Instant::now();
    let bar = ProgressBar::new(0).with_style(
        ProgressStyle::with_template("{spinner} {msg} [{bar:30}] {pos}/{len}")
            .expect("static template")
            .progress_chars("=> "),
    );
    bar.set_message("loading takes");
    let takes = offline::load_inputs(args.manifest.as_deref(), &args.files)?;
    bar.set_length(takes.len() as u64);
    bar.set_position(takes.len() as u64);
    let data = gather(&takes)?;
    let channels = data.labels.len() * 3;
    let fit_data = FitData::new(&data.samples, channels)?.with_missing(&data.missing)?;
    bar.set_style(ProgressStyle::with_template("{spinner} {msg} {elapsed}").expect("static"));
    bar.set_message(format!(
        "whitening and FastICA ({} restarts)",
        args.restarts
    ));
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    let fit = params.fit(&fit_data).context("training failed")?;
    bar.finish_and_clear();
    let model = IcaModel::new(data.labels, data.rate_hz, fit.mean, fit.mixing, fit.report)
        .context("the fitted model failed validation")?;
    let file = std::fs::File::create(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    model
        .save(std::io::BufWriter::new(file))
        .with_context(|| format!("cannot write {}", args.out.display()))?;
    print_summary(&model, takes.len(), started.elapsed().as_secs_f64())?;
    crate::out!("model: {}", args.out.display());
    Ok(())
}

fn print_summary(model: &IcaModel, takes: usize, seconds: f64) -> Result<()> {
    let r = model.report();
    let best = &r.restarts[r.best_restart];
    crate::out!(
        "trained on {takes} takes: used {} of {} frames, {} markers, {} dead channels",
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
        crate::out!(
            "  restart {i}: {} iterations, {}, negentropy {:.5}{}",
            run.iterations,
            if run.converged {
                "converged"
            } else {
                "NOT converged"
            },
            run.negentropy,
            if i == r.best_restart { "  <- kept" } else { "" }
        );
    }
    crate::out!(
        "kept restart {} ({}), {seconds:.2} s",
        r.best_restart,
        if best.converged {
            "converged"
        } else {
            "not converged: raise --max-iter"
        }
    );
    Ok(())
}
