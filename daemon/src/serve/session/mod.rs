//! `emoshift session`'s live half: the source runs for the whole session (the same as
//! `record`'s, [`super::capture::listen`]); each take is a [`Take`] the frames go into while it
//! records, checked the moment it stops ([`crate::offline::session::check`]); controls come
//! from the keyboard and from an OSC control socket under serve's rules (its `Guard`: loopback
//! by default, then the allow-list and the secret), and go through one [`Sitting`].

pub mod files;
mod keys;
mod osc;
pub mod view;

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use anyhow::{Context, Result};
use engine::SourceFrame;
use protocol::{Control, SessionControl};
use tokio::net::UdpSocket;
use tokio::sync::{mpsc, oneshot};
use tokio_util::sync::CancellationToken;

use super::allow::AllowList;
use super::capture::take::Take;
use super::capture::{self, Quiet, Source};
use super::guard::Guard;
use super::sources::Arrival;
use crate::offline::session::check::{self, Expect};
use crate::offline::session::{Sitting, State, Step};
use view::View;

/// What the session needs besides its [`Sitting`].
#[derive(Debug, Clone)]
pub struct SessionConfig {
    /// The session folder.
    pub dir: PathBuf,
    /// The live source.
    pub source: Source,
    /// The stream to record (the first seen when `None`).
    pub performer: Option<String>,
    /// The OSC control socket, if any.
    pub control: Option<SocketAddr>,
    /// Who may control over OSC.
    pub control_allow: AllowList,
    /// The secret mutating controls carry, if set.
    pub control_secret: Option<String>,
    /// Share of the model markers' samples a take must hold.
    pub min_seen: f64,
    /// Read controls from the keyboard (stdin).
    pub keyboard: bool,
    /// Serve the performer's view here.
    pub monitor: Option<SocketAddr>,
}

/// How the session ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ended {
    /// The operator asked to finish: train and analyse.
    Finish,
    /// Ctrl-C (the take being recorded is kept in `interrupted/`).
    Interrupted,
}

/// A control and where its answer goes (the encoded reply, or nothing for the keyboard).
struct Request {
    control: SessionControl,
    reply: Option<oneshot::Sender<Vec<u8>>>,
}

/// The take recording now, filled by the source's sink.
#[derive(Default)]
struct Live {
    take: Option<Take>,
    error: Option<anyhow::Error>,
}

/// Runs the session until finish or `shutdown`; `say` hears every line for the operator.
///
/// # Errors
/// A socket that cannot be bound, a take or the manifest that cannot be written.
pub async fn run(
    config: &SessionConfig,
    sitting: &mut Sitting,
    shutdown: CancellationToken,
    say: &mut (dyn FnMut(&str) + Send),
) -> Result<Ended> {
    let live = Mutex::new(Live::default());
    let quiet = Mutex::new(Quiet::default());
    let stop = shutdown.child_token();
    let (tx, mut rx) = mpsc::channel::<Request>(16);
    let control = bind_control(config.control).await?;
    if config.keyboard {
        keys::spawn(tx.clone());
    }
    let view = Arc::new(Mutex::new(View::default()));
    lock(&view).update(sitting);
    if let Some(addr) = config.monitor {
        let listener = tokio::net::TcpListener::bind(addr).await.with_context(|| {
            format!("binding the performer view {addr} (is another program on it?)")
        })?;
        say(&format!(
            "performer view: http://{}/",
            listener.local_addr()?
        ));
        tokio::spawn(view::serve(listener, view.clone(), stop.clone()));
    }
    let guard = Guard::with_rules(config.control_allow.clone(), config.control_secret.clone());
    let watch = config.monitor.is_some();
    let mut sink = |frame: &SourceFrame<'_>, arrival: &Arrival| {
        lock(&quiet).heard(arrival.received);
        if watch {
            let n = frame.labels.len();
            let seen = (0..n).filter(|&i| !frame.frame.is_missing(i)).count();
            let mut v = lock(&view);
            (v.markers_seen, v.markers) = (seen, n);
        }
        let mut l = lock(&live);
        let Live { take, error } = &mut *l;
        if let (Some(t), None) = (take.as_mut(), &error) {
            let stream = capture::stream_name(frame);
            if let Err(e) = t.push(&capture::incoming(frame, arrival, &stream)) {
                *error = Some(e);
            }
        }
    };
    let mut notice = |line: &str| tracing::warn!(target: "emoshift", "{line}");
    tell_prompt(sitting, say);
    let main = async {
        let r = steps(config, sitting, (&live, &view), &mut rx, &stop, say).await;
        stop.cancel();
        r
    };
    let (listened, ended, ()) = tokio::join!(
        capture::listen(&config.source, &quiet, &stop, &mut sink, &mut notice),
        main,
        osc::control_task(control, &guard, tx, &stop),
    );
    listened?;
    ended
}

/// The OSC control socket, when one is asked for.
async fn bind_control(addr: Option<SocketAddr>) -> Result<Option<Arc<UdpSocket>>> {
    let Some(addr) = addr else { return Ok(None) };
    let socket = UdpSocket::bind(addr).await.with_context(|| {
        format!("binding the session's control socket {addr} (is another program on it?)")
    })?;
    Ok(Some(Arc::new(socket)))
}

/// The controls, one at a time, until finish or `stop`.
async fn steps(
    config: &SessionConfig,
    sitting: &mut Sitting,
    (live, view): (&Mutex<Live>, &Mutex<View>),
    rx: &mut mpsc::Receiver<Request>,
    stop: &CancellationToken,
    say: &mut (dyn FnMut(&str) + Send),
) -> Result<Ended> {
    loop {
        let request = tokio::select! {
            () = stop.cancelled() => {
                interrupt(config, live, say)?;
                return Ok(Ended::Interrupted);
            }
            r = rx.recv() => match r {
                Some(r) => r,
                None => continue,
            },
        };
        let toggle = request.reply.is_none()
            && request.control == SessionControl::Start
            && *sitting.state() == State::Recording;
        let asked = match toggle {
            true => SessionControl::Stop,
            false => request.control,
        };
        let control = Control::Session(asked);
        let answer = match sitting.handle(asked) {
            Ok(step) => apply(config, sitting, live, step, say),
            Err(why) => Err(why),
        };
        let mut out = Vec::with_capacity(256);
        match &answer {
            Ok(_) if asked == SessionControl::Status => {
                protocol::encode_session_status_into(&sitting.status(), &mut out)
            }
            Ok(_) => protocol::encode_confirm_into(&control, &mut out),
            Err(why) => {
                if request.reply.is_none() {
                    say(why);
                }
                protocol::encode_error_into(control.address(), why, &mut out)
            }
        };
        lock(view).update(sitting);
        if let Some(reply) = request.reply {
            let _ = reply.send(out);
        }
        if answer == Ok(Some(Ended::Finish)) {
            return Ok(Ended::Finish);
        }
    }
}

/// Carries out a step; `Ok(Some(Finish))` ends the session. A take's I/O error is an `Err`
/// for the operator (the session goes on).
fn apply(
    config: &SessionConfig,
    sitting: &mut Sitting,
    live: &Mutex<Live>,
    step: Step,
    say: &mut (dyn FnMut(&str) + Send),
) -> Result<Option<Ended>, String> {
    match step {
        Step::Status => {}
        Step::Finish => return Ok(Some(Ended::Finish)),
        Step::Moved => tell_prompt(sitting, say),
        Step::Record { prompt, .. } => {
            let path = files::recording_path(&config.dir, &prompt, sitting.ext());
            let mut l = lock(live);
            l.error = None;
            l.take = Some(Take::new(&path, config.performer.clone()));
            drop(l);
            say(&format!(
                "● RECORDING take {} of {}: {} — \"{}\" (stop: Enter or /session/stop)",
                sitting.cursor() + 1,
                sitting.takes(),
                prompt.emotion,
                sitting.script().sentences[prompt.sentence].text
            ));
        }
        Step::Stop => {
            let outcome = stop_and_check(config, sitting, live).map_err(|e| format!("{e:#}"));
            let outcome = outcome.and_then(|checked| checked);
            match &outcome {
                Ok(_) => say(&format!(
                    "take accepted ({} of {} now)",
                    sitting.accepted() + 1,
                    sitting.takes()
                )),
                Err(why) => say(&format!("take REFUSED: {why}")),
            }
            let refused = outcome.as_ref().err().cloned();
            sitting.handle_checked(outcome);
            tell_prompt(sitting, say);
            if let Some(why) = refused {
                return Err(why);
            }
        }
    }
    Ok(None)
}

/// Closes the take, checks it, and puts it in place (accepted: its name, the manifest
/// written) or aside (`refused/`). The inner result is the check's: the rate, or why refused.
fn stop_and_check(
    config: &SessionConfig,
    sitting: &Sitting,
    live: &Mutex<Live>,
) -> Result<Result<f64, String>> {
    let (take, error) = {
        let mut l = lock(live);
        (l.take.take(), l.error.take())
    };
    let Some(take) = take else {
        return Ok(Err("nothing was recording".into()));
    };
    let relabelled = take.relabelled();
    let captured = take.finish()?;
    if let Some(e) = error {
        return Err(e);
    }
    let prompt = sitting.prompt().clone();
    let recording = files::recording_path(&config.dir, &prompt, sitting.ext());
    let Some(captured) = captured else {
        return Ok(Err(check::Refusal::Empty.to_string()));
    };
    let take = replay::load(&recording)
        .with_context(|| format!("cannot read back {}", recording.display()))?;
    let previous = match sitting.previous_accepted() {
        Some(p) => Some(replay::load(&config.dir.join(p.file_name(sitting.ext())))?),
        None => None,
    };
    let expect = Expect {
        seconds: sitting.script().sentences[prompt.sentence].seconds_range(),
        markers: previous.as_ref().map(|p| p.labels.as_slice()),
        min_seen: config.min_seen,
    };
    if let Err(refusal) = check::check(&take, relabelled, &expect, previous.as_ref()) {
        files::move_aside(&recording, &config.dir, "refused")?;
        return Ok(Err(refusal.to_string()));
    }
    accept(
        config,
        sitting,
        &recording,
        &prompt.file_name(sitting.ext()),
    )?;
    Ok(Ok(captured.rate_hz))
}

/// Puts an accepted take under its name (an accepted take it replaces goes to `replaced/`)
/// and writes the manifest with it.
fn accept(config: &SessionConfig, sitting: &Sitting, recording: &Path, name: &str) -> Result<()> {
    let final_path = config.dir.join(name);
    if final_path.exists() {
        files::move_aside(&final_path, &config.dir, "replaced")?;
    }
    std::fs::rename(recording, &final_path)
        .with_context(|| format!("cannot name the take {}", final_path.display()))?;
    let mut after = sitting.clone();
    after.handle_checked(Ok(0.0));
    if let Some(mut manifest) = after.manifest() {
        manifest.rate_hz = sitting.manifest().map_or(manifest.rate_hz, |m| m.rate_hz);
        files::write_manifest(&config.dir, &manifest)?;
    }
    Ok(())
}

/// Ctrl-C: a take being recorded is closed and kept in `interrupted/`.
fn interrupt(
    config: &SessionConfig,
    live: &Mutex<Live>,
    say: &mut (dyn FnMut(&str) + Send),
) -> Result<()> {
    let take = lock(live).take.take();
    if let Some(take) = take {
        take.finish()?;
        for p in files::set_aside_interrupted(&config.dir)? {
            say(&format!(
                "the take being recorded is kept as {}",
                p.display()
            ));
        }
    }
    say("session stopped; continue it with `emoshift session --resume` on the same folder");
    Ok(())
}

/// The prompt for the operator.
fn tell_prompt(sitting: &Sitting, say: &mut (dyn FnMut(&str) + Send)) {
    let p = sitting.prompt();
    let text = &sitting.script().sentences[p.sentence].text;
    match sitting.state() {
        State::Done => say(&format!(
            "all {} takes accepted: finish (f, /session/finish) to train and analyse, or retake the last (t)",
            sitting.takes()
        )),
        State::Review(_) => say(&format!(
            "retake (Enter, t or /session/retake) or skip (s) take {} of {}: {} — \"{text}\"",
            sitting.cursor() + 1,
            sitting.takes(),
            p.emotion
        )),
        _ => say(&format!(
            "NEXT take {} of {} (sentence {}): say it {} — \"{text}\"; Enter or /session/start records",
            sitting.cursor() + 1,
            sitting.takes(),
            p.sentence + 1,
            p.emotion.to_uppercase()
        )),
    }
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}
