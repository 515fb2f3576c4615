//! The performer's view (`session --monitor [IP:PORT]`): one page readable from a few metres
//! (the sentence in large text, the emotion, take n of N, a recording light, the markers
//! seen), refreshed from `/session.json` four times a second. It only shows: controls go
//! through the keyboard and the OSC control socket, whose rules guard them.

use std::net::SocketAddr;
use std::sync::{Arc, Mutex};

use axum::extract::State;
use axum::http::header;
use axum::response::IntoResponse;
use axum::routing::get;
use axum::Router;
use serde::Serialize;
use tokio::net::TcpListener;
use tokio_util::sync::CancellationToken;

use crate::offline::session::Sitting;

/// The performer view's default address.
pub const DEFAULT_VIEW: &str = "127.0.0.1:9080";

/// What the page shows.
#[derive(Debug, Clone, Default, Serialize, PartialEq)]
pub struct View {
    /// The prompted take, from 1.
    pub take: usize,
    /// Takes in the script.
    pub takes: usize,
    /// The sentence's number, from 1.
    pub sentence: usize,
    /// The emotion.
    pub emotion: String,
    /// The sentence.
    pub text: String,
    /// `waiting`, `recording`, `review` or `done`.
    pub state: String,
    /// Why the last take was refused, or empty.
    pub refused: String,
    /// Markers seen in the last frame.
    pub markers_seen: usize,
    /// Markers in the last frame.
    pub markers: usize,
}

impl View {
    /// The prompt of `sitting`, the marker counts kept.
    pub fn update(&mut self, sitting: &Sitting) {
        let st = sitting.status();
        self.take = (st.take as usize + 1).min(sitting.takes());
        self.takes = sitting.takes();
        self.sentence = st.sentence as usize;
        self.emotion = st.emotion;
        self.text = st.text;
        self.refused = match sitting.state() {
            crate::offline::session::State::Review(why) => why.clone(),
            _ => String::new(),
        };
        self.state = st.state;
    }
}

const PAGE: &str = r#"<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>emoshift session</title>
<meta name="viewport" content="width=device-width,initial-scale=1">
<style>
body{margin:0;background:#111;color:#eee;font-family:sans-serif;display:flex;flex-direction:column;height:100vh}
#top{display:flex;justify-content:space-between;align-items:center;padding:2vh 3vw;font-size:4vh}
#light{width:6vh;height:6vh;border-radius:50%;background:#333;display:inline-block;vertical-align:middle}
#light.on{background:#e0262b;box-shadow:0 0 4vh #e0262b}
#emotion{font-size:12vh;font-weight:bold;text-align:center;text-transform:uppercase;color:#f5c542}
#text{font-size:9vh;text-align:center;padding:0 4vw;flex:1;display:flex;align-items:center;justify-content:center}
#foot{font-size:3.5vh;padding:2vh 3vw;color:#aaa}
#refused{color:#ff8a80}
</style></head><body>
<div id="top"><span><span id="light"></span> <span id="state">connecting</span></span>
<span id="count"></span><span id="markers"></span></div>
<div id="emotion"></div><div id="text"></div>
<div id="foot"><span id="refused"></span></div>
<script src="view.js"></script></body></html>
"#;

const SCRIPT: &str = r#"const $ = (id) => document.getElementById(id);
async function tick() {
  try {
    const v = await (await fetch("session.json", {cache: "no-store"})).json();
    $("light").className = v.state === "recording" ? "on" : "";
    $("state").textContent = v.state;
    $("count").textContent = `take ${v.take} of ${v.takes} · sentence ${v.sentence}`;
    $("markers").textContent = `markers ${v.markers_seen} / ${v.markers}`;
    $("emotion").textContent = v.state === "done" ? "done" : v.emotion;
    $("text").textContent = v.state === "done" ? "Thank you." : v.text;
    $("refused").textContent = v.refused ? `refused: ${v.refused}` : "";
  } catch (e) {
    $("state").textContent = "session gone";
  }
}
setInterval(tick, 250);
tick();
"#;

/// Serves the page on `listener` until `stop`.
pub async fn serve(listener: TcpListener, view: Arc<Mutex<View>>, stop: CancellationToken) {
    let app = Router::new()
        .route(
            "/",
            get(|| async { ([(header::CONTENT_TYPE, "text/html; charset=utf-8")], PAGE) }),
        )
        .route(
            "/view.js",
            get(|| async { ([(header::CONTENT_TYPE, "text/javascript")], SCRIPT) }),
        )
        .route("/session.json", get(json))
        .with_state(view);
    let service = app.into_make_service_with_connect_info::<SocketAddr>();
    let served = axum::serve(listener, service)
        .with_graceful_shutdown(async move { stop.cancelled().await })
        .await;
    if let Err(e) = served {
        tracing::warn!(target: "emoshift", error = %e, "performer view stopped");
    }
}

async fn json(State(view): State<Arc<Mutex<View>>>) -> impl IntoResponse {
    let v = view.lock().map(|v| v.clone()).unwrap_or_default();
    (
        [
            (header::CONTENT_TYPE, "application/json"),
            (header::CACHE_CONTROL, "no-store"),
        ],
        serde_json::to_string(&v).unwrap_or_default(),
    )
}
