//! The control task: decodes control messages, routes them (edits, subscriptions, models and
//! recordings) to the processing thread, which applies them between frames, and answers each with
//! `<address>/confirm` or `/emoshift/error`. Model loads run on a blocking thread; SIGHUP
//! reloads the last model file.
//!
//! [`execute`] is the one command path: the control socket and the monitor page both call it
//! once their guard admitted the message, so the two never disagree.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use crossbeam_channel::Sender;
use ica_core::model::IcaModel;
use protocol::{
    encode_challenge_into, encode_confirm_into, encode_emotion_list_into, encode_error_into,
    encode_status_into, Control, EmotionList, StatusValue,
};
use tokio::net::UdpSocket;
use tokio::sync::oneshot;
use tokio_util::sync::CancellationToken;
use tokio_util::task::TaskTracker;

use super::command::{Command, Refusal, Reply, Request};
pub(crate) use super::guard::Guard;
use super::stats::Stats;
use super::wake::Doorbell;

/// How long a control message waits for the processing thread's answer.
const ANSWER_TIMEOUT: Duration = Duration::from_secs(2);

/// What the control task needs.
#[derive(Debug, Clone)]
pub(crate) struct ControlCtx {
    pub(crate) socket: Arc<UdpSocket>,
    pub(crate) cmd_tx: Sender<Request>,
    /// Wakes the processing thread to take a command.
    pub(crate) bell: Doorbell,
    pub(crate) stats: Arc<Mutex<Stats>>,
    /// The default model's file (SIGHUP reloads it); `None` before one is loaded.
    pub(crate) model_path: Arc<Mutex<Option<PathBuf>>>,
    /// The default model now (for `/emotion/list`); `None`: frames pass through unedited.
    pub(crate) model: Arc<Mutex<Option<Arc<IcaModel>>>>,
    pub(crate) tracker: TaskTracker,
    /// Who may control, and how.
    pub(crate) guard: Arc<Guard>,
}

/// Serves the control socket until shutdown.
pub(crate) async fn run(ctx: ControlCtx, shutdown: CancellationToken) {
    let mut buf = vec![0u8; protocol::MAX_UDP_PAYLOAD + 1];
    loop {
        let (len, peer) = tokio::select! {
            () = shutdown.cancelled() => break,
            r = ctx.socket.recv_from(&mut buf) => match r {
                Ok(r) => r,
                Err(e) => {
                    tracing::trace!(target: "emoshift", error = %e, "control socket receive error");
                    continue;
                }
            },
        };
        let control = match ctx
            .guard
            .admit(peer)
            .and_then(|()| ctx.guard.decode(&buf[..len]))
        {
            Ok(c) => c,
            Err(refusal) => {
                let address = refused_address(&buf[..len]);
                reply(&ctx, peer, &address, Err(refusal)).await;
                continue;
            }
        };
        if let Err(cookie) = ctx.guard.check_cookie(peer, &control) {
            // From beyond loopback a subscription starts only when the requester proves it
            // receives at its address: a spoofed source never sees the cookie.
            let mut out = Vec::with_capacity(64);
            encode_challenge_into(cookie, &mut out);
            send(&ctx, peer, &out).await;
            continue;
        }
        if let Control::ModelLoad(_) = &control {
            // Loading may take a while: answer from its own task, keep serving.
            let ctx2 = ctx.clone();
            ctx.tracker
                .spawn(async move { handle(&ctx2, peer, control).await });
            continue;
        }
        handle(&ctx, peer, control).await;
    }
}

/// The emotion space of a model as `/emotion/list/confirm` carries it.
fn emotion_list(model: &IcaModel) -> EmotionList {
    let e = model.emotion();
    EmotionList {
        components: e.space_components().iter().map(|&k| k as u32).collect(),
        emotions: e
            .names()
            .into_iter()
            .filter_map(|n| {
                let p = e.point(&n)?;
                Some((n, p.iter().map(|&v| v as f32).collect()))
            })
            .collect(),
    }
}

/// The address of a refused message, for the error reply (empty when unreadable).
fn refused_address(bytes: &[u8]) -> String {
    protocol::messages(bytes, &protocol::Limits::default())
        .ok()
        .and_then(|mut m| m.next())
        .map(|m| m.address.to_string())
        .unwrap_or_default()
}

/// What a control is answered with, whichever way it came.
#[derive(Debug)]
pub(crate) enum Answer {
    /// Done (`<address>/confirm`).
    Confirmed,
    /// Refused, and why (`/emoshift/error`); already counted and logged.
    Refused(Refusal),
    /// `/status`: the counters.
    Status(Vec<(String, StatusValue)>),
    /// `/emotion/list`: the default model's emotion space.
    EmotionList(EmotionList),
}

/// Answers a control over the control socket.
async fn handle(ctx: &ControlCtx, peer: SocketAddr, control: Control) {
    let mut out = Vec::with_capacity(2048);
    match execute(ctx, peer, &control, Some(peer)).await {
        Answer::Confirmed => encode_confirm_into(&control, &mut out),
        Answer::Refused(e) => encode_error_into(control.address(), &e.to_string(), &mut out),
        Answer::Status(pairs) => encode_status_into(&pairs, &mut out),
        Answer::EmotionList(list) => encode_emotion_list_into(&list, &mut out),
    };
    send(ctx, peer, &out).await;
}

/// Carries out a control the guard admitted (allow-list, secret, cookie): the one command
/// path of the control socket and the monitor page. A refusal is counted and logged here.
/// `osc_peer` hears later news of what it started over OSC (a recording that stops by itself).
pub(crate) async fn execute(
    ctx: &ControlCtx,
    peer: SocketAddr,
    control: &Control,
    osc_peer: Option<SocketAddr>,
) -> Answer {
    let result = match control {
        Control::Status => {
            let pairs = ctx.stats.lock().map(|s| s.pairs()).unwrap_or_default();
            return Answer::Status(pairs);
        }
        Control::EmotionList => match ctx.model.lock().map(|m| m.as_deref().map(emotion_list)) {
            Ok(Some(list)) => return Answer::EmotionList(list),
            Ok(None) => Err(Refusal::Edit(
                engine::edit_state::EditRefused::NoModel.to_string(),
            )),
            Err(_) => Err(Refusal::Model("model unavailable".into())),
        },
        Control::ModelLoad(path) => reload(ctx, PathBuf::from(path)).await,
        Control::Subscribe { .. } | Control::Unsubscribe { .. } => {
            let control = control.clone();
            ask(ctx, Command::Client { peer, control }).await
        }
        Control::RecordStart {
            path,
            raw,
            overwrite,
        } => {
            let raw = raw.as_ref().map(PathBuf::from);
            let (path, overwrite) = (PathBuf::from(path), *overwrite);
            ask(
                ctx,
                Command::RecordStart {
                    path,
                    raw,
                    overwrite,
                    controller: osc_peer,
                },
            )
            .await
        }
        Control::RecordStop => ask(ctx, Command::RecordStop).await,
        Control::Session(_) => Err(Refusal::Invalid(format!(
            "{} is a calibration session's control: send it to `emoshift session --control`, \
             not to serve",
            control.address()
        ))),
        other => ask(ctx, Command::Edit(other.clone())).await,
    };
    match result {
        Ok(()) => Answer::Confirmed,
        Err(e) => {
            count_refusal(ctx, peer, control.address(), &e);
            Answer::Refused(e)
        }
    }
}

/// Sends a command to the processing thread and waits for its answer.
async fn ask(ctx: &ControlCtx, command: Command) -> Reply {
    let (reply, rx) = oneshot::channel();
    ctx.cmd_tx
        .try_send(Request { command, reply })
        .map_err(|_| Refusal::Busy)?;
    ctx.bell.ring();
    match tokio::time::timeout(ANSWER_TIMEOUT, rx).await {
        Ok(Ok(r)) => r,
        Ok(Err(_)) => Err(Refusal::ShuttingDown),
        Err(_) => Err(Refusal::Timeout),
    }
}

/// Loads and validates a model on a blocking thread, then swaps it in at a frame boundary. A
/// bad file leaves the old model running.
async fn reload(ctx: &ControlCtx, path: PathBuf) -> Reply {
    let model = super::load_model(path.clone(), ctx.guard.max_model_bytes)
        .await
        .map_err(|e| Refusal::Model(format!("{e:#}")))?;
    let model = Arc::new(model);
    ask(ctx, Command::SetModel(Arc::clone(&model))).await?;
    if let Ok(mut p) = ctx.model_path.lock() {
        *p = Some(path.clone());
    }
    if let Ok(mut m) = ctx.model.lock() {
        *m = Some(model);
    }
    if let Ok(mut s) = ctx.stats.lock() {
        s.model = super::stats::model_name(Some(&path));
    }
    tracing::info!(target: "emoshift", path = %path.display(), "model swapped in");
    Ok(())
}

/// Counts a refused control (`control_refused`) and logs it, rate-limited.
pub(crate) fn count_refusal(ctx: &ControlCtx, peer: SocketAddr, address: &str, e: &Refusal) {
    if let Ok(mut s) = ctx.stats.lock() {
        s.control_refused += 1;
    }
    ctx.guard.warn_refused(peer, address, e);
}

/// Sends the error reply of a refused message (`Ok` sends nothing).
async fn reply(ctx: &ControlCtx, peer: SocketAddr, address: &str, r: Reply) {
    let Err(e) = r else { return };
    count_refusal(ctx, peer, address, &e);
    let mut out = Vec::with_capacity(256);
    encode_error_into(address, &e.to_string(), &mut out);
    send(ctx, peer, &out).await;
}

async fn send(ctx: &ControlCtx, peer: SocketAddr, bytes: &[u8]) {
    if let Err(e) = ctx.socket.send_to(bytes, peer).await {
        tracing::debug!(target: "emoshift", %peer, error = %e, "control reply not sent");
    }
}

/// Reloads the last model file on SIGHUP until shutdown.
pub(crate) async fn reload_on_sighup(ctx: ControlCtx, shutdown: CancellationToken) {
    #[cfg(unix)]
    {
        use tokio::signal::unix::{signal, SignalKind};
        let Ok(mut hup) = signal(SignalKind::hangup()) else {
            tracing::warn!(target: "emoshift", "cannot listen for SIGHUP; reload with /model/load");
            return;
        };
        loop {
            tokio::select! {
                () = shutdown.cancelled() => break,
                _ = hup.recv() => {
                    let path = ctx.model_path.lock().ok().and_then(|p| p.clone());
                    let Some(path) = path else {
                        tracing::warn!(target: "emoshift", "SIGHUP: no model file to reload, frames pass through unedited: load one with /model/load PATH");
                        continue;
                    };
                    match reload(&ctx, path).await {
                        Ok(()) => {}
                        Err(e) => tracing::warn!(target: "emoshift", error = %e, "SIGHUP reload failed, old model kept: fix the model file and send SIGHUP again, or /model/load another"),
                    }
                }
            }
        }
    }
    #[cfg(not(unix))]
    shutdown.cancelled().await;
}
