//! The monitor page without a browser (issue 17): its WebSocket feeds decimated snapshots and
//! takes controls through the control socket's own path, so an OSC subscriber sees what the
//! page set; the allow-list and the secret hold for the page as for OSC; beyond loopback the
//! page asks for a token; a foreign Origin or Host is refused.

use std::net::SocketAddr;
use std::time::{Duration, Instant};

use daemon::loopback::{self, ControlClient, Receiver, Source};
use daemon::serve::config::RawConfig;
use futures_util::{SinkExt, StreamExt};
use protocol::{encode_control_into, encode_control_signed_into, Control, Labels, Profile};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio_tungstenite::tungstenite::client::IntoClientRequest;
use tokio_tungstenite::tungstenite::Message;

use super::support::*;

type Ws =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

async fn daemon(m: &ModelFile, tweak: impl FnOnce(&mut RawConfig)) -> loopback::Daemon {
    let mut raw = RawConfig {
        listen: Some("127.0.0.1:0".into()),
        control: Some("127.0.0.1:0".into()),
        model: Some(m.path.clone()),
        monitor: Some("127.0.0.1:0".into()),
        ..RawConfig::default()
    };
    tweak(&mut raw);
    loopback::Daemon::start(raw.validate().expect("valid config"))
        .await
        .expect("daemon binds")
}

/// A page's WebSocket from `origin` (the page's own when `None`), with an optional cookie.
async fn open(at: SocketAddr, origin: Option<&str>, cookie: Option<&str>) -> Result<Ws, u16> {
    let mut req = format!("ws://{at}/ws").into_client_request().expect("url");
    let own = format!("http://{at}");
    let h = req.headers_mut();
    h.insert("origin", origin.unwrap_or(&own).parse().expect("header"));
    if let Some(c) = cookie {
        h.insert("cookie", c.parse().expect("header"));
    }
    match tokio_tungstenite::connect_async(req).await {
        Ok((ws, _)) => Ok(ws),
        Err(tokio_tungstenite::tungstenite::Error::Http(r)) => Err(r.status().as_u16()),
        Err(e) => panic!("websocket: {e}"),
    }
}

/// The next JSON text of `kind`, skipping snapshots and other texts.
async fn next_json(ws: &mut Ws, kind: &str) -> serde_json::Value {
    let deadline = Instant::now() + Duration::from_secs(5);
    while Instant::now() < deadline {
        let msg = tokio::time::timeout(Duration::from_secs(5), ws.next()).await;
        if let Ok(Some(Ok(Message::Text(t)))) = msg {
            let v: serde_json::Value = serde_json::from_str(&t).expect("json");
            if v["type"] == kind {
                return v;
            }
        }
    }
    panic!("no {kind} message within 5 s");
}

/// Sends a control as the page does (an OSC message) and returns the page's reply.
async fn page_control(ws: &mut Ws, c: &Control, secret: Option<&str>) -> serde_json::Value {
    let mut bytes = Vec::new();
    match secret {
        Some(s) => encode_control_signed_into(c, s, &mut bytes),
        None => encode_control_into(c, &mut bytes),
    };
    ws.send(Message::Binary(bytes.into())).await.expect("sent");
    next_json(ws, "reply").await
}

/// Sends `n` frames from `source`, numbered from `from`, paced a little.
async fn frames(source: &mut Source, m: &ModelFile, from: usize, n: usize) {
    for (k, xyz) in take_frames(&m.model, from + n)
        .iter()
        .enumerate()
        .skip(from)
    {
        source
            .send_frame(k as i32, k as i64, xyz, &[])
            .expect("finite");
        tokio::time::sleep(Duration::from_millis(4)).await;
    }
}

fn source(d: &loopback::Daemon, m: &ModelFile) -> Source {
    let labels = Labels {
        layout_id: 0,
        names: m.model.labels().to_vec(),
    };
    Source::on_loopback(&labels, d.frames).expect("source")
}

#[tokio::test]
async fn the_page_steers_through_the_osc_path_and_sees_the_frames_it_changed() {
    let m = model_file(17);
    let d = daemon(&m, |_| {}).await;
    let at = d.monitor.expect("monitor bound");
    let control = ControlClient::new(d.control).await.expect("client");
    let sub = Receiver::subscribe(&control, Profile::Compact)
        .await
        .expect("subscribed");
    let states = sub.collect(None, Vec::new(), |got, r| {
        if let Some(s) = &r.state {
            got.push((s.target.to_string(), s.amount));
        }
    });
    let mut ws = open(at, None, None).await.expect("upgraded");
    let hello = next_json(&mut ws, "hello").await;
    assert_eq!(hello["control"]["allowed"], true);
    let mut src = source(&d, &m);
    frames(&mut src, &m, 0, 30).await;
    let model = next_json(&mut ws, "model").await;
    assert_eq!(
        model["labels"][0], "m0",
        "the page is told the stream's model: {model}"
    );
    for c in [
        Control::Ramp(0.0),
        Control::Target("happy".into()),
        Control::Amount(0.5),
    ] {
        let r = page_control(&mut ws, &c, None).await;
        assert_eq!(r["ok"], true, "{r}");
    }
    let r = page_control(&mut ws, &Control::Target("furious".into()), None).await;
    assert!(
        r["error"]
            .as_str()
            .expect("why")
            .contains("unknown emotion \"furious\" (the model knows "),
        "{r}"
    );
    let sub_from_page = Control::Subscribe {
        port: 9,
        profile: Profile::Compact,
        performer: None,
        cookie: None,
    };
    assert_eq!(
        page_control(&mut ws, &sub_from_page, None).await["ok"],
        false
    );
    frames(&mut src, &m, 30, 60).await;
    // The page's feed: snapshots of the stream with the state the engine applied.
    let mut snapshots = 0;
    let deadline = Instant::now() + Duration::from_secs(3);
    while Instant::now() < deadline && snapshots < 5 {
        match tokio::time::timeout(Duration::from_secs(1), ws.next()).await {
            Ok(Some(Ok(Message::Binary(b)))) if &b[..4] == b"EMF1" => {
                let t = u32::from_le_bytes(b[60..64].try_into().expect("4")) as usize;
                if &b[64..64 + t] == b"happy" {
                    snapshots += 1;
                }
            }
            _ => {}
        }
    }
    let seen = states.stop().await.expect("receiver");
    let status = control.status().await.expect("status");
    d.stop(Duration::from_secs(2)).await.expect("stops");
    assert!(
        snapshots >= 5,
        "snapshots of the edited stream: {snapshots}"
    );
    assert_eq!(
        seen.last().map(|(t, a)| (t.as_str(), *a)),
        Some(("happy", 0.5)),
        "the OSC subscriber sees what the page set"
    );
    assert_eq!(loopback::counter(&status, "control_refused"), Some(2));
    assert_eq!(loopback::counter(&status, "monitor_viewers"), Some(1));
}

#[tokio::test]
async fn page_control_obeys_the_allow_list_and_the_secret() {
    let m = model_file(18);
    let d = daemon(&m, |r| r.control_allow = Some(vec!["10.0.0.0/8".into()])).await;
    let mut ws = open(d.monitor.expect("bound"), None, None)
        .await
        .expect("up");
    let hello = next_json(&mut ws, "hello").await;
    assert_eq!(hello["control"]["allowed"], false, "view only: {hello}");
    let r = page_control(&mut ws, &Control::Amount(1.0), None).await;
    assert!(
        r["error"].as_str().expect("why").contains("not allowed"),
        "{r}"
    );
    d.stop(Duration::from_secs(2)).await.expect("stops");

    let d = daemon(&m, |r| r.control_secret = Some("s3cret".into())).await;
    let mut ws = open(d.monitor.expect("bound"), None, None)
        .await
        .expect("up");
    assert_eq!(next_json(&mut ws, "hello").await["control"]["secret"], true);
    let r = page_control(&mut ws, &Control::Amount(1.0), None).await;
    assert!(r["error"].as_str().expect("why").contains("secret"), "{r}");
    let r = page_control(&mut ws, &Control::Amount(1.0), Some("wrong")).await;
    assert_eq!(r["ok"], false, "{r}");
    let r = page_control(&mut ws, &Control::Amount(1.0), Some("s3cret")).await;
    assert_eq!(r["ok"], true, "{r}");
    let r = page_control(&mut ws, &Control::Status, None).await;
    assert_eq!(r["status"]["control_refused"], 2, "{r}");
    d.stop(Duration::from_secs(2)).await.expect("stops");
}

/// The status line and headers of a plain GET.
async fn get(at: SocketAddr, path: &str, host: &str, cookie: Option<&str>) -> String {
    let mut s = tokio::net::TcpStream::connect(at).await.expect("connects");
    let cookie = cookie
        .map(|c| format!("Cookie: {c}\r\n"))
        .unwrap_or_default();
    let req = format!("GET {path} HTTP/1.1\r\nHost: {host}\r\n{cookie}Connection: close\r\n\r\n");
    s.write_all(req.as_bytes()).await.expect("sent");
    let mut out = Vec::new();
    tokio::time::timeout(Duration::from_secs(5), s.read_to_end(&mut out))
        .await
        .expect("answered")
        .expect("read");
    String::from_utf8_lossy(&out).into_owned()
}

#[tokio::test]
async fn beyond_loopback_a_token_then_a_cookie_and_foreign_origins_never() {
    let m = model_file(19);
    let token = "stage-token-0123456789";
    let d = daemon(&m, |r| {
        r.monitor = Some("127.0.0.2:0".into());
        r.monitor_token = Some(token.into());
    })
    .await;
    let at = d.monitor.expect("bound");
    let host = at.to_string();
    let first = get(at, "/", &host, None).await;
    assert!(
        first.starts_with("HTTP/1.1 401") && first.contains("name=\"token\""),
        "{first}"
    );
    assert!(
        !first.contains("main.js"),
        "nothing of the page before the token"
    );
    assert!(get(at, "/js/main.js", &host, None)
        .await
        .starts_with("HTTP/1.1 401"));
    let wrong = get(at, "/?token=stage-token-9876543210", &host, None).await;
    assert!(wrong.contains("not this daemon"), "{wrong}");
    let right = get(at, &format!("/?token={token}"), &host, None).await;
    assert!(right.starts_with("HTTP/1.1 303"), "{right}");
    let cookie = format!("emoshift_monitor_{}={token}", at.port());
    assert!(
        right.contains(&cookie) && right.contains("HttpOnly"),
        "{right}"
    );
    let page = get(at, "/", &host, Some(&cookie)).await;
    assert!(
        page.starts_with("HTTP/1.1 200") && page.contains("js/main.js"),
        "{page}"
    );
    assert!(page
        .to_lowercase()
        .contains("content-security-policy: default-src 'self'"));
    assert_eq!(open(at, None, None).await.err(), Some(401));
    assert_eq!(
        open(at, Some("http://evil.example"), Some(&cookie))
            .await
            .err(),
        Some(403)
    );
    let mut ws = open(at, None, Some(&cookie))
        .await
        .expect("the page's own origin");
    assert_eq!(next_json(&mut ws, "hello").await["type"], "hello");
    // The monitor's counters reach /status with its next health tick (4 a second).
    tokio::time::sleep(Duration::from_millis(400)).await;
    let status = ControlClient::new(d.control).await.expect("client");
    let refused = loopback::counter(&status.status().await.expect("status"), "monitor_refused");
    d.stop(Duration::from_secs(2)).await.expect("stops");
    assert!(
        refused >= Some(3),
        "wrong token, websocket without it, foreign origin: {refused:?}"
    );
}

#[tokio::test]
async fn on_loopback_no_token_but_a_rebound_host_name_is_refused() {
    let m = model_file(20);
    let d = daemon(&m, |_| {}).await;
    let at = d.monitor.expect("bound");
    assert!(get(at, "/", &at.to_string(), None)
        .await
        .starts_with("HTTP/1.1 200"));
    let port = at.port();
    assert!(get(at, "/style.css", &format!("localhost:{port}"), None)
        .await
        .starts_with("HTTP/1.1 200"));
    let rebound = get(at, "/", &format!("attacker.example:{port}"), None).await;
    assert!(rebound.starts_with("HTTP/1.1 403"), "{rebound}");
    assert_eq!(
        open(at, Some("http://attacker.example"), None).await.err(),
        Some(403)
    );
    d.stop(Duration::from_secs(2)).await.expect("stops");
}
