//! `emoshift session`'s live half: the source runs for the whole session (the same as
//! `record`'s, [`super::capture::listen`]); each take is a [`Take`] the frames go into while it
//! records, checked the moment it stops ([`crate::offline::session::check`]); controls come
//! from the keyboard, from an OSC control socket and from the performer page's buttons, the
//! last two under serve's rules (its `Guard`: loopback by default, then the allow-list and the
//! secret), and go through one [`Sitting`]. Finish trains and analyses (a [`Finisher`], off
//! the runtime) while the source and the page run on; when it says what to redo, the session
//! offers to record just those takes again now.

pub mod files;
mod finish;
mod keys;
mod osc;
mod stopped;
pub mod view;

use std::net::SocketAddr;
use std::path::PathBuf;
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
use crate::offline::session::advice::Advice;
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
    /// The token the performer's view asks for (a random one when it is bound beyond this
    /// host and none is given).
    pub monitor_token: Option<String>,
}

/// Trains and analyses the accepted takes, saying what to redo; blocking (run off the
/// runtime), and it tells the operator its progress itself.
pub type Finisher = Arc<dyn Fn() -> Result<Advice> + Send + Sync>;

/// How the session ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ended {
    /// Finished: the model is trained (and analysed), its redo offer taken or declined.
    Finish,
    /// Ctrl-C (the take being recorded is kept in `interrupted/`).
    Interrupted,
}

/// A control and where its answer goes (nothing for the keyboard).
struct Request {
    control: SessionControl,
    reply: Option<oneshot::Sender<Answer>>,
}

/// A control's answer: the OSC reply, and why the control was refused (for the page).
struct Answer {
    osc: Vec<u8>,
    refused: Option<String>,
}

/// What the loop does after a control.
#[derive(Debug, PartialEq)]
enum After {
    /// Take the next control.
    Next,
    /// Train and analyse.
    Finish,
    /// End the session (the model stands).
    Close,
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
    finish: Finisher,
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
    let (view, guard) = page(config, sitting, &tx, &stop, say).await?;
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
        let r = steps(
            config,
            (sitting, &finish),
            (&live, &view),
            &mut rx,
            &stop,
            say,
        )
        .await;
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

/// The view and the control rules, and the performer page when one is asked for.
async fn page(
    config: &SessionConfig,
    sitting: &Sitting,
    tx: &mpsc::Sender<Request>,
    stop: &CancellationToken,
    say: &mut (dyn FnMut(&str) + Send),
) -> Result<(Arc<Mutex<View>>, Arc<Guard>)> {
    let view = Arc::new(Mutex::new(View::default()));
    lock(&view).update(sitting);
    let guard = Arc::new(Guard::with_rules(
        config.control_allow.clone(),
        config.control_secret.clone(),
    ));
    if let Some(addr) = config.monitor {
        let page = (view.clone(), guard.clone(), tx.clone());
        view::spawn(addr, config.monitor_token.clone(), page, stop.clone(), say).await?;
    }
    Ok((view, guard))
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
    (sitting, finish): (&mut Sitting, &Finisher),
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
                // No control left (no keyboard, socket or page): only Ctrl-C ends it.
                None => {
                    stop.cancelled().await;
                    continue;
                }
            },
        };
        let toggle = request.reply.is_none()
            && request.control == SessionControl::Start
            && *sitting.state() == State::Recording;
        let asked = match toggle {
            true => SessionControl::Stop,
            false => request.control,
        };
        let after = match sitting.handle(asked) {
            Ok(step) => apply(config, sitting, live, step, say),
            Err(why) => Err(why),
        };
        if let (Err(why), None) = (&after, &request.reply) {
            say(why);
        }
        let answer = answer(sitting, asked, after.as_ref().err());
        lock(view).update(sitting);
        if let Some(reply) = request.reply {
            let _ = reply.send(answer);
        }
        match after {
            Ok(After::Close) => return Ok(Ended::Finish),
            Ok(After::Finish) => {
                let advice = finish::finishing(sitting, finish, rx, view).await?;
                if finish::offer(sitting, &advice, view, say)? {
                    return Ok(Ended::Finish);
                }
            }
            _ => {}
        }
    }
}

/// The answer to `asked`: the status, its confirmation, or why it was refused.
fn answer(sitting: &Sitting, asked: SessionControl, refused: Option<&String>) -> Answer {
    let control = Control::Session(asked);
    let mut osc = Vec::with_capacity(256);
    match refused {
        None if asked == SessionControl::Status => {
            protocol::encode_session_status_into(&sitting.status(), &mut osc)
        }
        None => protocol::encode_confirm_into(&control, &mut osc),
        Some(why) => protocol::encode_error_into(control.address(), why, &mut osc),
    };
    Answer {
        osc,
        refused: refused.cloned(),
    }
}

/// Carries out a step. A take's I/O error is an `Err` for the operator (the session goes
/// on).
fn apply(
    config: &SessionConfig,
    sitting: &mut Sitting,
    live: &Mutex<Live>,
    step: Step,
    say: &mut (dyn FnMut(&str) + Send),
) -> Result<After, String> {
    match step {
        Step::Status => {}
        Step::Finish => {
            say("finishing: training and analysing the accepted takes ...");
            return Ok(After::Finish);
        }
        Step::Close => {
            say("the session ends with this model");
            return Ok(After::Close);
        }
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
            let outcome =
                stopped::stop_and_check(config, sitting, live).map_err(|e| format!("{e:#}"));
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
    Ok(After::Next)
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
