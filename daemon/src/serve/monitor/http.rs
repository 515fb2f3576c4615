//! The routes: `/` the page, `/ws` its WebSocket, the page's files by path; every response
//! with headers that keep the page to itself (a content security policy of `'self'` only, no
//! framing, no referrer: the token may be in the address). A request without access gets the
//! login prompt, whatever it asked for.

use std::net::SocketAddr;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use axum::extract::{ConnectInfo, State, WebSocketUpgrade};
use axum::http::{header, HeaderMap, HeaderValue, StatusCode, Uri};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use axum::Router;
use tokio::net::TcpListener;

use super::access::{Access, Verdict};
use super::{socket, Monitor};

/// The page's files, embedded: (path, content type, text).
const FILES: &[(&str, &str, &str)] = &[
    ("/", HTML, include_str!("../../../web/index.html")),
    ("/style.css", CSS, include_str!("../../../web/style.css")),
    ("/js/main.js", JS, include_str!("../../../web/js/main.js")),
    ("/js/feed.js", JS, include_str!("../../../web/js/feed.js")),
    (
        "/js/canvas.js",
        JS,
        include_str!("../../../web/js/canvas.js"),
    ),
    ("/js/osc.js", JS, include_str!("../../../web/js/osc.js")),
    ("/js/face.js", JS, include_str!("../../../web/js/face.js")),
    ("/js/strip.js", JS, include_str!("../../../web/js/strip.js")),
    (
        "/js/control.js",
        JS,
        include_str!("../../../web/js/control.js"),
    ),
    (
        "/js/health.js",
        JS,
        include_str!("../../../web/js/health.js"),
    ),
    (
        "/favicon.svg",
        SVG,
        include_str!("../../../web/favicon.svg"),
    ),
];
const LOGIN: &str = include_str!("../../../web/login.html");

pub(crate) const HTML: &str = "text/html; charset=utf-8";
pub(crate) const CSS: &str = "text/css; charset=utf-8";
pub(crate) const JS: &str = "text/javascript; charset=utf-8";
const SVG: &str = "image/svg+xml";

pub(crate) const PAGE_POLICY: &str = "default-src 'self'; script-src 'self'; style-src 'self'; \
    img-src 'self' data:; connect-src 'self'; frame-ancestors 'none'; base-uri 'none'; \
    form-action 'self'";
/// The login prompt carries its own style and nothing else.
const LOGIN_POLICY: &str =
    "default-src 'none'; style-src 'unsafe-inline'; form-action 'self'; frame-ancestors 'none'";

/// Serves until shutdown.
pub(crate) async fn serve(listener: TcpListener, m: Arc<Monitor>) {
    let shutdown = m.shutdown.clone();
    let app = Router::new()
        .route("/ws", get(ws))
        .fallback(get(file))
        .with_state(m);
    let service = app.into_make_service_with_connect_info::<SocketAddr>();
    let served = axum::serve(listener, service)
        .with_graceful_shutdown(async move { shutdown.cancelled().await })
        .await;
    if let Err(e) = served {
        tracing::warn!(target: "emoshift", error = %e, "monitor page stopped: the daemon runs on; restart serve to get the page back");
    }
}

pub(crate) fn header_str(headers: &HeaderMap, name: header::HeaderName) -> Option<&str> {
    headers.get(name).and_then(|v| v.to_str().ok())
}

/// `None` when the request may be served; otherwise the answer it gets. A wrong token is
/// counted in `refused`, and with `strict` (the WebSocket, a control, which no first visit
/// sends) a missing one too.
pub(crate) fn gate(
    (access, refused): (&Access, &AtomicU64),
    headers: &HeaderMap,
    uri: &Uri,
    strict: bool,
) -> Option<Response> {
    let host = header_str(headers, header::HOST);
    let cookie = header_str(headers, header::COOKIE);
    match access.check(host, uri.query(), cookie) {
        Verdict::Allow => None,
        Verdict::SetCookie => {
            let mut r = (StatusCode::SEE_OTHER, [(header::LOCATION, uri.path())]).into_response();
            if let Some(c) = access
                .set_cookie()
                .and_then(|c| HeaderValue::from_str(&c).ok())
            {
                r.headers_mut().insert(header::SET_COOKIE, c);
            }
            Some(secure(r, LOGIN_POLICY))
        }
        Verdict::Login { wrong } => {
            if wrong || strict {
                refused.fetch_add(1, Ordering::Relaxed);
                tracing::debug!(target: "emoshift", wrong, "monitor page: no or a wrong token");
            }
            let note = if wrong {
                "That token is not this daemon's."
            } else {
                ""
            };
            let body = LOGIN.replace("{{note}}", note);
            let r = (
                StatusCode::UNAUTHORIZED,
                [(header::CONTENT_TYPE, HTML)],
                body,
            );
            Some(secure(r.into_response(), LOGIN_POLICY))
        }
        Verdict::BadHost => {
            refused.fetch_add(1, Ordering::Relaxed);
            let r = (
                StatusCode::FORBIDDEN,
                "this page answers to its own address only\n",
            );
            Some(secure(r.into_response(), LOGIN_POLICY))
        }
    }
}

/// One of the page's files.
async fn file(State(m): State<Arc<Monitor>>, headers: HeaderMap, uri: Uri) -> Response {
    if let Some(r) = gate((&m.access, &m.hub.refused), &headers, &uri, false) {
        return r;
    }
    page_file(FILES, &uri)
}

/// The file of `files` (path, content type, text) that `uri` names, or 404, with the page's
/// security headers: the monitor's and the session view's files are served the same way.
pub(crate) fn page_file(files: &[(&str, &'static str, &'static str)], uri: &Uri) -> Response {
    match files.iter().find(|(path, _, _)| *path == uri.path()) {
        Some((_, kind, text)) => secure(
            ([(header::CONTENT_TYPE, *kind)], *text).into_response(),
            PAGE_POLICY,
        ),
        None => secure(StatusCode::NOT_FOUND.into_response(), PAGE_POLICY),
    }
}

/// The page's WebSocket: its Origin must be the page's own.
async fn ws(
    State(m): State<Arc<Monitor>>,
    ConnectInfo(peer): ConnectInfo<SocketAddr>,
    headers: HeaderMap,
    uri: Uri,
    upgrade: WebSocketUpgrade,
) -> Response {
    if let Some(r) = gate((&m.access, &m.hub.refused), &headers, &uri, true) {
        return r;
    }
    let host = header_str(&headers, header::HOST);
    if !m
        .access
        .origin_ok(host, header_str(&headers, header::ORIGIN))
    {
        m.hub.refused.fetch_add(1, Ordering::Relaxed);
        tracing::debug!(target: "emoshift", %peer, "monitor WebSocket from a foreign origin refused");
        return (StatusCode::FORBIDDEN, "foreign origin\n").into_response();
    }
    if m.hub.full() {
        m.hub.refused.fetch_add(1, Ordering::Relaxed);
        return (
            StatusCode::SERVICE_UNAVAILABLE,
            "too many monitor pages open\n",
        )
            .into_response();
    }
    upgrade
        .max_message_size(socket::MAX_MESSAGE_BYTES)
        .max_frame_size(socket::MAX_MESSAGE_BYTES)
        .on_upgrade(move |s| socket::run(m, s, peer))
}

/// Adds the headers every response carries.
pub(crate) fn secure(mut r: Response, policy: &'static str) -> Response {
    let h = r.headers_mut();
    h.insert(
        header::CONTENT_SECURITY_POLICY,
        HeaderValue::from_static(policy),
    );
    h.insert(header::X_FRAME_OPTIONS, HeaderValue::from_static("DENY"));
    h.insert(
        header::X_CONTENT_TYPE_OPTIONS,
        HeaderValue::from_static("nosniff"),
    );
    h.insert(
        header::REFERRER_POLICY,
        HeaderValue::from_static("no-referrer"),
    );
    h.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    r
}
