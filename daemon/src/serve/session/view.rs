//! The performer's page (`session --monitor [IP:PORT]`): readable from a few metres (the
//! sentence in large text, the emotion, take n of N, a recording light, the markers seen),
//! refreshed from `/session.json` four times a second, with big buttons for a touch screen
//! (start, stop, retake, skip, back, finish, and the redo a finish offers).
//!
//! The page is held to serve's monitor rules with serve's code: `monitor::access` (loopback
//! by default, a token beyond it, Host and Origin checked) and `monitor::http::gate`. A press
//! is posted to `/control` as the OSC message the control socket takes (the page encodes it
//! with serve's `osc.js`) and goes through the same `admit` as the OSC socket: serve's `Guard`,
//! the allow-list by the page's address, the secret as the last argument. The answer says why
//! a press was refused, and the page shows it.

use std::net::SocketAddr;
use std::sync::atomic::AtomicU64;
use std::sync::{Arc, Mutex};

use anyhow::{Context, Result};
use axum::body::Bytes;
use axum::extract::{ConnectInfo, DefaultBodyLimit, State};
use axum::http::{header, HeaderMap, StatusCode, Uri};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::Router;
use serde::Serialize;
use serde_json::json;
use tokio::net::TcpListener;
use tokio::sync::mpsc;
use tokio_util::sync::CancellationToken;

use super::Request;
use crate::offline::session::{Sitting, State as Phase};
use crate::serve::guard::Guard;
use crate::serve::monitor::access::Access;
use crate::serve::monitor::http::{
    gate, header_str, page_file, secure, CSS, HTML, JS, PAGE_POLICY,
};

/// The performer view's default address.
pub const DEFAULT_VIEW: &str = "127.0.0.1:9080";
/// Largest control a page may post (a control message is a few dozen bytes).
const MAX_CONTROL_BYTES: usize = 4096;

/// What the page shows.
#[derive(Debug, Clone, Default, Serialize, PartialEq)]
pub struct View {
    /// The prompted take, from 1.
    pub take: usize,
    /// Takes in the script.
    pub takes: usize,
    /// Takes accepted.
    pub accepted: usize,
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
    /// Training and analysing (a finish under way).
    pub finishing: bool,
    /// What the last finish said to redo, in plain words (while its offer stands).
    pub advice: Vec<String>,
    /// The takes the last finish offers to record again (`/session/redo`).
    pub offered: Vec<String>,
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
        self.accepted = sitting.accepted();
        self.sentence = st.sentence as usize;
        self.emotion = st.emotion;
        self.text = st.text;
        self.refused = match sitting.state() {
            Phase::Review(why) => why.clone(),
            _ => String::new(),
        };
        self.state = st.state;
        self.offered = sitting.offered();
        if self.offered.is_empty() {
            self.advice.clear();
        }
    }
}

/// The page's files: (path, content type, text).
const FILES: &[(&str, &str, &str)] = &[
    ("/", HTML, include_str!("../../../web/session.html")),
    (
        "/session.css",
        CSS,
        include_str!("../../../web/session.css"),
    ),
    (
        "/js/session.js",
        JS,
        include_str!("../../../web/js/session.js"),
    ),
    ("/js/osc.js", JS, include_str!("../../../web/js/osc.js")),
];

/// What the page's handlers share.
struct Page {
    view: Arc<Mutex<View>>,
    guard: Arc<Guard>,
    access: Access,
    tx: mpsc::Sender<Request>,
    /// Requests refused (token, host, origin).
    refused: AtomicU64,
}

/// Binds the page at `addr`, says its address (with the token when one is needed), and serves
/// it until `stop`.
///
/// # Errors
/// The address cannot be bound.
pub(super) async fn spawn(
    addr: SocketAddr,
    token: Option<String>,
    (view, guard, tx): (Arc<Mutex<View>>, Arc<Guard>, mpsc::Sender<Request>),
    stop: CancellationToken,
    say: &mut (dyn FnMut(&str) + Send),
) -> Result<()> {
    let listener = TcpListener::bind(addr).await.with_context(|| {
        format!("binding the performer view {addr} (is another program on it?)")
    })?;
    let bound = listener.local_addr()?;
    let access = Access::new(bound, token);
    let query = access
        .token()
        .map(|t| format!("?token={t}"))
        .unwrap_or_default();
    say(&format!("performer view: http://{bound}/{query}"));
    let page = Arc::new(Page {
        view,
        guard,
        access,
        tx,
        refused: AtomicU64::new(0),
    });
    tokio::spawn(serve(listener, page, stop));
    Ok(())
}

async fn serve(listener: TcpListener, page: Arc<Page>, stop: CancellationToken) {
    let app = Router::new()
        .route("/session.json", get(json))
        .route("/control", post(control))
        .fallback(get(file))
        .layer(DefaultBodyLimit::max(MAX_CONTROL_BYTES))
        .with_state(page);
    let service = app.into_make_service_with_connect_info::<SocketAddr>();
    let served = axum::serve(listener, service)
        .with_graceful_shutdown(async move { stop.cancelled().await })
        .await;
    if let Err(e) = served {
        tracing::warn!(target: "emoshift", error = %e, "performer view stopped: the session runs on (keyboard, OSC)");
    }
}

async fn file(State(page): State<Arc<Page>>, headers: HeaderMap, uri: Uri) -> Response {
    if let Some(r) = gate((&page.access, &page.refused), &headers, &uri, false) {
        return r;
    }
    page_file(FILES, &uri)
}

/// The view's fields, and what this page may do (`control`: allowed, why not, whether the
/// secret is needed), by the asking page's address.
async fn json(
    State(page): State<Arc<Page>>,
    ConnectInfo(peer): ConnectInfo<SocketAddr>,
    headers: HeaderMap,
    uri: Uri,
) -> Response {
    if let Some(r) = gate((&page.access, &page.refused), &headers, &uri, false) {
        return r;
    }
    let view = page.view.lock().map(|v| v.clone()).unwrap_or_default();
    let allowed = page.guard.admit(peer);
    let mut body = serde_json::to_value(view).unwrap_or_default();
    body["control"] = json!({
        "allowed": allowed.is_ok(),
        "why": allowed.err().map(|e| e.to_string()),
        "secret": page.guard.needs_secret(),
    });
    let r = (
        [(header::CONTENT_TYPE, "application/json")],
        body.to_string(),
    );
    secure(r.into_response(), PAGE_POLICY)
}

/// A press: the OSC message in the body, from the page's own origin, through the session's
/// control rules; answered `{"ok": true}` or `{"ok": false, "error": why}`.
async fn control(
    State(page): State<Arc<Page>>,
    ConnectInfo(peer): ConnectInfo<SocketAddr>,
    headers: HeaderMap,
    uri: Uri,
    body: Bytes,
) -> Response {
    if let Some(r) = gate((&page.access, &page.refused), &headers, &uri, true) {
        return r;
    }
    let host = header_str(&headers, header::HOST);
    let answer = match page
        .access
        .origin_ok(host, header_str(&headers, header::ORIGIN))
    {
        true => super::osc::admit(&page.guard, &page.tx, peer, &body).await,
        false => {
            page.refused
                .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            let why = "a press from another site's page is refused: use this page";
            let r = (
                StatusCode::FORBIDDEN,
                json!({ "ok": false, "error": why }).to_string(),
            );
            return secure(r.into_response(), PAGE_POLICY);
        }
    };
    let body = match answer {
        Some(a) => json!({ "ok": a.refused.is_none(), "error": a.refused }),
        None => json!({ "ok": false, "error": "the session has ended" }),
    };
    let r = (
        [(header::CONTENT_TYPE, "application/json")],
        body.to_string(),
    );
    secure(r.into_response(), PAGE_POLICY)
}
