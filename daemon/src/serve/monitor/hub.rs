//! The pages' side of the board: every page's queues, the snapshots fanned out to them, the
//! health four times a second. A page that does not keep up loses feed messages (counted);
//! one whose text queue (health, models, replies) fills is disconnected. Nothing here grows
//! with a slow page.

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use axum::extract::ws::Message;
use ica_core::model::IcaModel;
use serde_json::json;
use tokio::sync::mpsc;

use super::board::Board;
use super::status::{Health, Latency};
use super::{wire, Monitor, MAX_VIEWERS};
use crate::serve::stats::MonitorCounters;

/// Feed messages queued per page: past it, the newest is dropped for that page.
const FEED_QUEUE: usize = 4;
/// Text messages queued per page: a page this far behind is disconnected.
const TEXT_QUEUE: usize = 64;
/// Health messages a second.
const STATUS_EVERY: Duration = Duration::from_millis(250);

/// One open page, as the hub sends to it.
#[derive(Debug)]
struct Viewer {
    id: u64,
    feed: mpsc::Sender<Message>,
    texts: mpsc::Sender<Message>,
}

/// One open page, as its socket task reads its queues.
#[derive(Debug)]
pub(crate) struct Joined {
    pub(crate) id: u64,
    pub(crate) feed: mpsc::Receiver<Message>,
    pub(crate) texts: mpsc::Receiver<Message>,
}

/// The models the pages were last told about.
#[derive(Debug, Default)]
struct Known {
    /// Per stream id: its model and the `model` message describing it.
    streams: HashMap<i32, (Arc<IcaModel>, String)>,
    /// The default model and its `emotions` message (the buttons).
    default: Option<(Arc<IcaModel>, String)>,
}

/// The open pages and what they were sent.
#[derive(Debug)]
pub(crate) struct Hub {
    viewers: Mutex<Vec<Viewer>>,
    next_id: AtomicU64,
    board: Arc<Board>,
    known: Mutex<Known>,
    /// Feed messages dropped for slow pages.
    pub(crate) dropped: AtomicU64,
    /// Requests refused (token, host, origin, too many pages).
    pub(crate) refused: AtomicU64,
}

impl Hub {
    pub(crate) fn new(board: Arc<Board>) -> Hub {
        Hub {
            viewers: Mutex::new(Vec::with_capacity(MAX_VIEWERS)),
            next_id: AtomicU64::new(1),
            board,
            known: Mutex::new(Known::default()),
            dropped: AtomicU64::new(0),
            refused: AtomicU64::new(0),
        }
    }

    /// Whether another page may open.
    pub(crate) fn full(&self) -> bool {
        self.viewers.lock().map_or(true, |v| v.len() >= MAX_VIEWERS)
    }

    /// Adds a page, queued the models known so far; `None` when [`MAX_VIEWERS`] are open.
    pub(crate) fn join(&self) -> Option<Joined> {
        let (feed_tx, feed) = mpsc::channel(FEED_QUEUE);
        let (texts_tx, texts) = mpsc::channel(TEXT_QUEUE);
        if let Ok(known) = self.known.lock() {
            let first = known.default.iter().map(|d| &d.1);
            for text in first.chain(known.streams.values().map(|s| &s.1)) {
                let _ = texts_tx.try_send(Message::Text(text.as_str().into()));
            }
        }
        let mut viewers = self.viewers.lock().ok()?;
        if viewers.len() >= MAX_VIEWERS {
            return None;
        }
        let id = self.next_id.fetch_add(1, Ordering::Relaxed);
        viewers.push(Viewer {
            id,
            feed: feed_tx,
            texts: texts_tx,
        });
        self.board.set_viewers(viewers.len());
        Some(Joined { id, feed, texts })
    }

    /// Removes a page.
    pub(crate) fn leave(&self, id: u64) {
        if let Ok(mut viewers) = self.viewers.lock() {
            viewers.retain(|v| v.id != id);
            self.board.set_viewers(viewers.len());
        }
    }

    /// Sends a feed message to every page that has room; the others lose it (counted).
    fn feed(&self, bytes: Vec<u8>) {
        let message = Message::Binary(bytes.into());
        let Ok(viewers) = self.viewers.lock() else {
            return;
        };
        for v in viewers.iter() {
            if v.feed.try_send(message.clone()).is_err() {
                self.dropped.fetch_add(1, Ordering::Relaxed);
            }
        }
    }

    /// Sends a text to every page; a page whose queue is full is disconnected.
    fn text(&self, text: &str) {
        let Ok(mut viewers) = self.viewers.lock() else {
            return;
        };
        let message = Message::Text(text.into());
        viewers.retain(|v| match v.texts.try_send(message.clone()) {
            Ok(()) => true,
            Err(_) => {
                tracing::warn!(target: "emoshift", "monitor page too slow, disconnected: reload the page; on a slow network open it nearer the daemon");
                false
            }
        });
        self.board.set_viewers(viewers.len());
    }

    fn counters(&self) -> MonitorCounters {
        MonitorCounters {
            viewers: self.viewers.lock().map_or(0, |v| v.len() as u64),
            dropped: self.dropped.load(Ordering::Relaxed),
            unpublished: self.board.unpublished(),
            refused: self.refused.load(Ordering::Relaxed),
        }
    }
}

/// The hub's task: snapshots out as they are published, health every [`STATUS_EVERY`].
pub(crate) async fn run(m: Arc<Monitor>) {
    let mut tick = tokio::time::interval(STATUS_EVERY);
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
    let (mut seen, mut ticks) = (0u64, 0u64);
    let mut latency = Latency::default();
    loop {
        tokio::select! {
            () = m.shutdown.cancelled() => break,
            () = m.board.published() => seen = fan_out(&m, seen),
            _ = tick.tick() => {
                status(&m, &mut latency, ticks % 4 == 0);
                ticks += 1;
            }
        }
    }
}

/// Encodes each fresh snapshot once and sends it to every page; a stream's model, when new
/// to the pages, goes first.
fn fan_out(m: &Monitor, seen: u64) -> u64 {
    let mut fresh = Vec::new();
    let top = m.board.fresh(seen, |s| {
        fresh.push((s.stream_id, s.model.clone(), wire::encode_snapshot(s)));
    });
    for (id, model, bytes) in fresh {
        if let Some(model) = model {
            tell_model(m, id, &model);
        }
        m.hub.feed(bytes);
    }
    top
}

/// Sends the `model` message of stream `id` when its model is new to the pages.
fn tell_model(m: &Monitor, id: i32, model: &Arc<IcaModel>) {
    let Ok(mut known) = m.hub.known.lock() else {
        return;
    };
    if known
        .streams
        .get(&id)
        .is_some_and(|(k, _)| Arc::ptr_eq(k, model))
    {
        return;
    }
    let default = m.ctx.model.lock().ok().and_then(|d| d.clone());
    let file = match default.is_some_and(|d| Arc::ptr_eq(&d, model)) {
        true => m.stats.lock().ok().map(|s| s.model.clone()),
        false => None,
    };
    let text = wire::model_json(id, model, file.as_deref());
    m.hub.text(&text);
    known.streams.insert(id, (Arc::clone(model), text));
}

/// The health to every page; the default model's emotions when it changed; slots of streams
/// gone dropped. With `sample`, this second's latency histograms are kept.
fn status(m: &Monitor, latency: &mut Latency, sample: bool) {
    let counters = m.hub.counters();
    let (health, hists, alive) = {
        let Ok(mut s) = m.stats.lock() else { return };
        s.monitor = counters;
        let hists = sample.then(|| (s.processed_us.clone(), s.sent_us.clone()));
        let alive: Vec<i32> = s.per_stream.iter().map(|st| st.id).collect();
        (Health::of(&s), hists, alive)
    };
    if let Some((processed, sent)) = hists {
        latency.observe(processed, sent);
    }
    m.board.retain(|id| alive.contains(&id));
    if let Ok(mut known) = m.hub.known.lock() {
        known.streams.retain(|id, _| alive.contains(id));
    }
    tell_emotions(m);
    m.hub.text(&health.into_message(latency, counters));
}

/// Sends the default model's emotions (the page's buttons) when the model changed.
fn tell_emotions(m: &Monitor) {
    let Some(model) = m.ctx.model.lock().ok().and_then(|d| d.clone()) else {
        return;
    };
    let Ok(mut known) = m.hub.known.lock() else {
        return;
    };
    if known
        .default
        .as_ref()
        .is_some_and(|(k, _)| Arc::ptr_eq(k, &model))
    {
        return;
    }
    let text = json!({ "type": "emotions", "emotion": wire::emotion_json(&model) }).to_string();
    m.hub.text(&text);
    known.default = Some((model, text));
}

#[cfg(test)]
mod tests;
