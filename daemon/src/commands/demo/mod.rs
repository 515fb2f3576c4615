//! `emoshift demo [--keep DIR] [--real]`: the whole chain on an embedded default, in a minute.
//!
//! 1. a paired synthetic session (or, with `--real`, the bundled Facial-Sing capture);
//! 2. train and analyse a model (progress and summaries as `train` and `analyze` print them);
//! 3. the daemon on loopback (ephemeral ports), in this process;
//! 4. a neutral take replayed into it at its rate while the emotion sweeps through named
//!    emotions of the model's emotion space over OSC control (no sweep without emotion pairs);
//! 5. a client subscribed with the compact profile receives the edited stream;
//! 6. a summary: frames, loss, latency percentiles, the emotion state seen, the components and
//!    their roles, and the path of the HTML report.
//!
//! With `--monitor [IP:PORT]`, steps 4 to 6 become: the daemon with the monitor page served,
//! the take looping until Ctrl-C. Everything live goes through the loopback harness
//! ([`crate::loopback`]); training and analysis are `train`'s and `analyze`'s own functions.

mod live;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result};
use replay::session::Regions;
use replay::synth::{write_session, SynthParams};

use super::analyze::{analyze_and_write, Report};
use super::train::{options_with_regions, train_and_save};
use crate::cli::DemoArgs;
use crate::offline::training::TrainOptions;

/// The bundled real capture (NaturalPoint ARENA, 38 markers at 100 Hz; see
/// replay/tests/fixtures/SOURCE.md) and the regions read off its geometry.
const FACIAL_SING: &[u8] = include_bytes!("../../../../replay/tests/fixtures/Facial-Sing.c3d");
const FACIAL_SING_REGIONS: &str = include_str!("../../../tests/fixtures/facial-sing.regions.toml");
const FACIAL_SING_MANIFEST: &str =
    "rate_hz = 100\n\n[[take]]\nfile = \"Facial-Sing.c3d\"\nsentence = \"song\"\nemotion = \"singing\"\n";

/// Sentences of the demo session: 8 x 4 emotions over 2 emotion directions, about 13,000
/// frames at 120 Hz.
const SENTENCES: usize = 8;
/// Seconds of live streaming (the take loops).
const STREAM_S: f64 = 12.0;

fn step(n: usize, text: &str) -> Result<()> {
    crate::out!("\n== {n}/5 {text}");
    Ok(())
}

pub(crate) fn run(args: &DemoArgs) -> Result<()> {
    let started = Instant::now();
    let Some(dir) = &args.keep else {
        let dir = tempfile::Builder::new()
            .prefix("emoshift-demo-")
            .tempdir()
            .context("cannot create a temporary folder")?
            .keep();
        let result = chain(args, &dir, started);
        // Only the report stays, so the path in the summary opens; the rest was scaffolding.
        for entry in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
            if entry.file_name() != "report" {
                let path = entry.path();
                let _ = std::fs::remove_dir_all(&path).or_else(|_| std::fs::remove_file(&path));
            }
        }
        if result.is_ok() {
            crate::out!(
                "(session and model were temporary; `emoshift demo --keep DIR` keeps them)"
            );
        }
        return result;
    };
    crate::offline::output::check_out_dir(dir, false)?;
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    chain(args, dir, started)
}

/// The inputs of training and analysis, the take to stream, and the emotions to sweep
/// through while streaming (none without emotion pairs).
struct Session {
    manifest: PathBuf,
    regions: Option<PathBuf>,
    take: PathBuf,
    sweep: Vec<String>,
}

fn chain(args: &DemoArgs, dir: &Path, started: Instant) -> Result<()> {
    let session = if args.real {
        step(
            1,
            "the bundled real capture (Facial-Sing, 38 markers at 100 Hz)",
        )?;
        real_session(dir)?
    } else {
        step(1, "a paired synthetic session (8 sentences x neutral, happy, sad, angry over 2 emotion directions)")?;
        synthetic_session(dir, args.seed)?
    };
    step(2, "training the ICA model")?;
    let model_path = dir.join("model.json");
    let takes = crate::offline::load_inputs(Some(&session.manifest), &[])?;
    let options = match &session.regions {
        Some(path) => options_with_regions(Regions::load(path)?),
        None => TrainOptions::default(),
    };
    train_and_save(&takes, &options, &model_path)?;
    step(3, "analysing the components")?;
    let report = Report {
        dir: &dir.join("report"),
        write_model: true,
        axes: crate::offline::analysis::Axes::default(),
    };
    let regions = session.regions.as_deref();
    let (model, _) = analyze_and_write(&model_path, &session.manifest, regions, &report)?;
    let take = Arc::new(crate::offline::load_take(&session.take)?);
    if let Some(addr) = &args.monitor {
        step(
            4,
            "serving on loopback with the monitor page, the take looping",
        )?;
        return live::serve_with_monitor(&model, take, addr);
    }
    step(4, "serving on loopback and replaying a take through it")?;
    let live = live::stream(&model, take, &session.sweep)?;
    step(5, "summary")?;
    live::summary(&live, &model, &report.dir.join("report.html"), started)
}

fn synthetic_session(dir: &Path, seed: u64) -> Result<Session> {
    let params = SynthParams {
        seed,
        sentences: SENTENCES,
        emotions: ["neutral", "happy", "sad", "angry"]
            .map(String::from)
            .to_vec(),
        emotion_dims: 2,
        ..SynthParams::default()
    };
    let s = dir.join("session");
    let summary = write_session(&s, &params, replay::Format::C3d)
        .with_context(|| format!("cannot write the session to {}", s.display()))?;
    let (takes, frames) = (summary.takes.len(), summary.total_frames);
    crate::out!(
        "wrote {takes} takes, {frames} frames, {} markers to {}",
        summary.markers,
        s.display()
    );
    Ok(Session {
        manifest: summary.manifest,
        regions: None,
        take: s.join("s01_neutral.c3d"),
        sweep: ["sad", "happy", "angry"].map(String::from).to_vec(),
    })
}

fn real_session(dir: &Path) -> Result<Session> {
    let (take, regions, manifest) = (
        dir.join("Facial-Sing.c3d"),
        dir.join("regions.toml"),
        dir.join("session.toml"),
    );
    for (path, bytes) in [
        (&take, FACIAL_SING),
        (&regions, FACIAL_SING_REGIONS.as_bytes()),
        (&manifest, FACIAL_SING_MANIFEST.as_bytes()),
    ] {
        std::fs::write(path, bytes).with_context(|| format!("cannot write {}", path.display()))?;
    }
    crate::out!(
        "wrote {}, its regions and a one-take manifest (no emotion pairs)",
        take.display()
    );
    Ok(Session {
        manifest,
        regions: Some(regions),
        take,
        sweep: Vec::new(),
    })
}
