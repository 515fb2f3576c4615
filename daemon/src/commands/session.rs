//! `emoshift session DIR`: a new performer's paired calibration session from a live source
//! ([`crate::serve::session`]); on finish, training and analysis of what was recorded into
//! `DIR/model.json` and `DIR/report/` (the session offers to re-record, there and then, the
//! takes the analysis says to redo), and with `--load-into` the model sent to a running
//! `serve`.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result};
use replay::session::Regions;
use tokio_util::sync::CancellationToken;

use crate::cli::SessionArgs;
use crate::exit::UsageError;
use crate::offline::session::advice::{advise, Advice};
use crate::offline::session::script::{Script, DEFAULT_SENTENCES};
use crate::offline::session::Sitting;
use crate::serve::allow::AllowList;
use crate::serve::session::files::{self, MANIFEST, SCRIPT};
use crate::serve::session::{self as live, Ended, Finisher, SessionConfig};

/// The arguments, checked, and the session folder made ready.
fn config(args: &SessionArgs) -> Result<SessionConfig> {
    let source = super::record::source(
        args.listen.as_ref(),
        args.natnet.as_ref(),
        args.qtm.as_ref(),
        &args.natnet_options,
    )?;
    let control = args
        .control
        .as_ref()
        .map(|c| {
            c.parse()
                .map_err(|_| UsageError(format!("--control: {c:?} is not an IP:PORT address")))
        })
        .transpose()?;
    let control_allow = match args.control_allow.is_empty() {
        true => AllowList::loopback(),
        false => AllowList::parse(&args.control_allow)
            .map_err(|e| UsageError(format!("--control-allow: {e}")))?,
    };
    if !(0.5..=1.0).contains(&args.min_seen) {
        return Err(UsageError(format!("--min-seen {}: expected 0.5 to 1", args.min_seen)).into());
    }
    if replay::Format::from_name(&args.format).is_none() {
        let f = &args.format;
        return Err(UsageError(format!("--format {f:?}: expected c3d, trc or csv")).into());
    }
    Ok(SessionConfig {
        dir: args.dir.clone(),
        source,
        performer: args.performer.clone(),
        control,
        control_allow,
        control_secret: args.control_secret.clone(),
        min_seen: args.min_seen,
        keyboard: !args.no_keyboard,
        monitor: args
            .monitor
            .as_ref()
            .map(|m| {
                m.parse()
                    .map_err(|_| UsageError(format!("--monitor: {m:?} is not an IP:PORT address")))
            })
            .transpose()?,
        monitor_token: crate::serve::config::check_token(args.monitor_token.clone())
            .map_err(|e| UsageError(format!("--monitor-token: {e}")))?,
    })
}

/// A new session's folder and script, or the resumed session's.
fn sitting(args: &SessionArgs) -> Result<Sitting> {
    let dir = &args.dir;
    let script_path = dir.join(SCRIPT);
    if args.resume {
        if !script_path.exists() {
            return Err(UsageError(format!(
                "--resume: {} holds no session ({SCRIPT} is missing): start one without --resume",
                dir.display()
            ))
            .into());
        }
        let script = read_script(&script_path)?;
        for p in files::set_aside_interrupted(dir)? {
            crate::out!(
                "the take interrupted last time is kept as {}; it is offered again",
                p.display()
            );
        }
        let manifest = dir.join(MANIFEST);
        let mut sitting = match manifest.exists() {
            true => Sitting::resume(
                script,
                &args.format,
                &crate::offline::load_session(&manifest)?,
            ),
            false => Sitting::new(script, &args.format),
        };
        if !args.redo.is_empty() {
            sitting
                .redo(&args.redo)
                .map_err(|e| UsageError(format!("--{e}")))?;
        }
        return Ok(sitting);
    }
    if script_path.exists() || dir.join(MANIFEST).exists() {
        return Err(UsageError(format!(
            "{} holds a session already: add --resume to continue it, or choose another folder",
            dir.display()
        ))
        .into());
    }
    let script = match &args.script {
        Some(path) => read_script(path)?,
        None => Script::harvard(DEFAULT_SENTENCES),
    };
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    files::write_atomically(&script_path, &script.to_toml())?;
    Ok(Sitting::new(script, &args.format))
}

fn read_script(path: &Path) -> Result<Script> {
    // Bounded like every text input: `--script /dev/zero` is refused, not read forever.
    let text = replay::file::read_to_string_bounded(path, replay::file::DEFAULT_MAX_TEXT_BYTES)
        .with_context(|| format!("cannot read the script {}", path.display()))?;
    Script::parse(&text).map_err(|e| UsageError(format!("{}: {e}", path.display())).into())
}

pub(crate) fn run(args: &SessionArgs) -> Result<()> {
    let config = config(args)?;
    let mut sitting = sitting(args)?;
    if let Some(regions) = &args.regions {
        Regions::load(regions)?;
        std::fs::copy(regions, args.dir.join("regions.toml"))
            .with_context(|| format!("cannot copy {} into the session", regions.display()))?;
    }
    crate::out!(
        "session in {}: {} sentences x {} emotions = {} takes, {} accepted",
        args.dir.display(),
        sitting.script().sentences.len(),
        sitting.script().emotions.len(),
        sitting.takes(),
        sitting.accepted()
    );
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("starting the tokio runtime")?;
    let ended = runtime.block_on(async {
        let shutdown = CancellationToken::new();
        tokio::spawn(super::serve::cancel_on_signal(shutdown.clone()));
        let mut say = |line: &str| {
            use std::io::Write;
            // The operator's lines; a closed stdout (piped into a pager that quit) ends none.
            let _ = writeln!(std::io::stdout().lock(), "{line}");
        };
        live::run(&config, &mut sitting, finisher(args), shutdown, &mut say).await
    })?;
    if ended == Ended::Interrupted {
        return Ok(());
    }
    if let Some(to) = &args.load_into {
        runtime.block_on(load_into(to, &args.dir.join("model.json")))?;
    }
    Ok(())
}

/// What finishing needs of the arguments.
struct Finishing {
    dir: PathBuf,
    format: String,
    /// The source's flag, for the printed `--resume --redo` command.
    source: String,
}

/// The session's finish: [`finish`], then what to redo.
fn finisher(args: &SessionArgs) -> Finisher {
    let source = match (&args.listen, &args.natnet, &args.qtm) {
        (Some(l), _, _) => format!("--listen {l}"),
        (_, Some(n), _) => format!("--natnet {n}"),
        (_, _, Some(q)) => format!("--qtm {q}"),
        _ => String::new(),
    };
    let f = Finishing {
        dir: args.dir.clone(),
        format: args.format.clone(),
        source,
    };
    Arc::new(move || finish(&f))
}

/// Trains on the accepted takes into `DIR/model.json` (an older one goes to `replaced/`),
/// analyses them into `DIR/report/` when the session has a regions file, and says what to
/// redo.
fn finish(args: &Finishing) -> Result<Advice> {
    let dir = args.dir.as_path();
    let manifest = dir.join(MANIFEST);
    let session = crate::offline::load_session(&manifest)?;
    let model_path = dir.join("model.json");
    if model_path.exists() {
        files::move_aside(&model_path, dir, "replaced")?;
    }
    let regions_path = dir.join("regions.toml");
    let regions = regions_path.exists().then_some(&regions_path);
    crate::out!("training on {} takes ...", session.takes.len());
    super::train::train_session(&manifest, regions.map(PathBuf::as_path), &model_path)?;
    if regions.is_none() {
        crate::out!(
            "no regions.toml in {}: the model is trained but not analysed (roles, emotion \
             space); add one (--regions FILE with --resume, then finish) to analyse",
            dir.display()
        );
        return Ok(Advice::default());
    }
    crate::out!("analysing ...");
    let report = super::analyze::Report {
        dir: &dir.join("report"),
        write_model: true,
        axes: crate::offline::analysis::Axes::default(),
    };
    let (_, report) = super::analyze::analyze_and_write(&model_path, &manifest, None, &report)?;
    let advice = advise(&report);
    tell_advice(args, &advice)?;
    Ok(advice)
}

/// What to redo, and the command that records just those takes again in a later sitting.
fn tell_advice(args: &Finishing, advice: &Advice) -> Result<()> {
    if advice.lines.is_empty() {
        crate::out!("nothing to redo: every emotion stands apart and no take is an outlier");
        return Ok(());
    }
    crate::out!("to redo:");
    for line in &advice.lines {
        crate::out!("  - {line}");
    }
    if !advice.redo.is_empty() {
        let source = &args.source;
        let takes: Vec<&str> = advice
            .redo
            .iter()
            .map(|f| f.trim_end_matches(&format!(".{}", args.format)))
            .collect();
        crate::out!(
            "in a later sitting: emoshift session {} {source} --resume --redo {}",
            args.dir.display(),
            takes.join(",")
        );
    }
    Ok(())
}

/// `/model/load` of the model to a running serve's control socket, and its answer.
async fn load_into(to: &str, model: &Path) -> Result<()> {
    let addr = tokio::net::lookup_host(to)
        .await
        .ok()
        .and_then(|mut a| a.next())
        .ok_or_else(|| UsageError(format!("--load-into: {to:?} is not a HOST:PORT address")))?;
    let path = std::fs::canonicalize(model)?;
    let client = crate::loopback::ControlClient::new(addr).await?;
    let control = protocol::Control::ModelLoad(path.display().to_string());
    match client.request(&control).await {
        Ok(protocol::Reply::Confirm(_)) => {
            crate::out!("serve at {addr} loaded {}", path.display());
            Ok(())
        }
        Ok(other) => anyhow::bail!("serve at {addr} did not load the model: {other:?}"),
        Err(e) => Err(e.context(format!(
            "no answer from serve at {addr}: is it running with --control {to}?"
        ))),
    }
}
