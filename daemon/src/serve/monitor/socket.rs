//! One page's WebSocket: its queues out (texts before the feed), control messages in. A
//! control arrives as the OSC message the control socket would take (the page encodes it)
//! and goes through the same guard and the same [`execute`]: the allow-list by the page's
//! address, the shared secret as the last argument, the same range checks, the same counters.

use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;

use axum::extract::ws::{Message, WebSocket};
use futures_util::stream::SplitSink;
use futures_util::{SinkExt, StreamExt};
use protocol::{Control, StatusValue};
use serde_json::{json, Value};

use super::hub::Joined;
use super::Monitor;
use crate::serve::command::Refusal;
use crate::serve::control::{count_refusal, execute, Answer};
use engine::monitor::DEFAULT_MONITOR_HZ;

/// A page that takes longer than this to accept one message is disconnected.
const SEND_TIMEOUT: Duration = Duration::from_secs(5);
/// Largest message a page may send (a control message is a few hundred bytes).
pub(crate) const MAX_MESSAGE_BYTES: usize = 4096;

/// Serves one page until it leaves, falls behind, or the daemon shuts down.
pub(crate) async fn run(m: Arc<Monitor>, socket: WebSocket, peer: SocketAddr) {
    let Some(joined) = m.hub.join() else {
        return;
    };
    let id = joined.id;
    tracing::info!(target: "emoshift", %peer, "monitor page opened");
    serve(&m, socket, peer, joined).await;
    m.hub.leave(id);
    tracing::info!(target: "emoshift", %peer, "monitor page closed");
}

async fn serve(m: &Monitor, socket: WebSocket, peer: SocketAddr, mut joined: Joined) {
    let (mut tx, mut rx) = socket.split();
    if !send(&mut tx, Message::Text(hello(m, peer).into())).await {
        return;
    }
    loop {
        let out = tokio::select! {
            biased;
            () = m.shutdown.cancelled() => Some(Message::Close(None)),
            msg = joined.texts.recv() => msg,
            msg = joined.feed.recv() => msg,
            msg = rx.next() => match msg {
                Some(Ok(Message::Binary(bytes))) => {
                    Some(Message::Text(command(m, peer, &bytes).await.into()))
                }
                // Pings are answered by the library; texts are not controls.
                Some(Ok(Message::Ping(_) | Message::Pong(_) | Message::Text(_))) => continue,
                _ => None,
            },
        };
        let Some(out) = out else { break };
        let closing = matches!(out, Message::Close(_));
        if !send(&mut tx, out).await || closing {
            break;
        }
    }
}

/// Sends one message; `false` when the page is gone or took longer than [`SEND_TIMEOUT`].
async fn send(tx: &mut SplitSink<WebSocket, Message>, msg: Message) -> bool {
    matches!(
        tokio::time::timeout(SEND_TIMEOUT, tx.send(msg)).await,
        Ok(Ok(()))
    )
}

/// The first message: what this page may do.
fn hello(m: &Monitor, peer: SocketAddr) -> String {
    let allowed = m.ctx.guard.admit(peer);
    json!({
        "type": "hello",
        "version": 1,
        "hz": DEFAULT_MONITOR_HZ,
        "control": {
            "allowed": allowed.is_ok(),
            "why": allowed.err().map(|e| e.to_string()),
            "secret": m.ctx.guard.needs_secret(),
        },
    })
    .to_string()
}

/// Carries out one control from the page and answers it (`reply`).
async fn command(m: &Monitor, peer: SocketAddr, bytes: &[u8]) -> String {
    let address = protocol::messages(bytes, &protocol::Limits::default())
        .ok()
        .and_then(|mut msgs| msgs.next())
        .map(|msg| msg.address.to_string())
        .unwrap_or_default();
    let guard = &m.ctx.guard;
    let admitted = guard.admit(peer).and_then(|()| guard.decode(bytes));
    let answer = match admitted {
        Ok(Control::Subscribe { .. } | Control::Unsubscribe { .. }) => {
            let e = Refusal::Invalid("subscriptions are made over the control socket".into());
            count_refusal(&m.ctx, peer, &address, &e);
            Answer::Refused(e)
        }
        Ok(control) => execute(&m.ctx, peer, &control, None).await,
        Err(e) => {
            count_refusal(&m.ctx, peer, &address, &e);
            Answer::Refused(e)
        }
    };
    reply(&address, answer).to_string()
}

/// The `reply` message of an answer.
fn reply(address: &str, answer: Answer) -> Value {
    let mut v = json!({ "type": "reply", "address": address, "ok": true });
    match answer {
        Answer::Confirmed => {}
        Answer::Refused(e) => {
            v["ok"] = json!(false);
            v["error"] = json!(e.to_string());
        }
        Answer::Status(pairs) => {
            let map: serde_json::Map<String, Value> = pairs
                .into_iter()
                .map(|(k, v)| {
                    let v = match v {
                        StatusValue::Int(i) => json!(i),
                        StatusValue::Text(t) => json!(t),
                    };
                    (k, v)
                })
                .collect();
            v["status"] = Value::Object(map);
        }
        Answer::EmotionList(list) => {
            v["emotions"] = json!(list
                .emotions
                .iter()
                .map(|(name, level)| json!({ "name": name, "level": level }))
                .collect::<Vec<_>>());
            v["components"] = json!(list.components);
        }
    }
    v
}
