//! A stage the service can trust: performers told apart and labelled, subscriptions that
//! survive (static) and expire (dynamic), cookies against spoofed subscriptions, control only
//! from allowed peers with the secret, checked values, refused duplicate labels, hot swaps
//! that never leave a stream stuck, and recordings that overwrite nothing by surprise. Valid
//! frames keep flowing throughout, and none is lost.

use std::collections::BTreeMap;
use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

use daemon::loopback::{self, ControlClient, Receiver, Source};
use daemon::serve::config::RawConfig;
use protocol::{Control, Labels, Profile, Reply};

use super::support::*;

const QUIET: Duration = Duration::from_millis(400);

/// A daemon on `m` with the config changed by `tweak`.
async fn daemon(m: &ModelFile, tweak: impl FnOnce(&mut RawConfig)) -> loopback::Daemon {
    let mut raw = RawConfig {
        listen: Some("127.0.0.1:0".into()),
        control: Some("127.0.0.1:0".into()),
        model: Some(m.path.clone()),
        queue: Some(4096),
        ..RawConfig::default()
    };
    tweak(&mut raw);
    loopback::Daemon::start(raw.validate().expect("valid config"))
        .await
        .expect("daemon binds")
}

async fn stop(d: loopback::Daemon) {
    d.stop(Duration::from_secs(2)).await.expect("stops cleanly");
}

fn labels(m: &ModelFile) -> Labels {
    Labels {
        layout_id: 0,
        names: m.model.labels().to_vec(),
    }
}

/// A source on a fresh socket at `local`.
fn source_at(local: &str, m: &ModelFile, to: SocketAddr) -> Source {
    let socket = UdpSocket::bind(local).expect("bind");
    let mut s = Source::new(&labels(m), socket, to, false).expect("labels encode");
    s.send_labels();
    s
}

/// Sends frames `range` of `frames` from `source`, pausing now and then so that only the
/// daemon could lose one.
async fn send(source: &mut Source, frames: &[Vec<f32>], range: std::ops::Range<usize>) {
    for n in range {
        source
            .send_frame(n as i32, n as i64, &frames[n], &[])
            .expect("finite");
        if n % 8 == 7 {
            tokio::time::sleep(Duration::from_millis(1)).await;
        }
    }
}

/// What a receiver saw, per stream name: frame numbers, and the labels and stream id it got
/// before that stream's first frame.
#[derive(Debug, Default)]
struct Seen {
    frames: BTreeMap<String, Vec<i32>>,
    ids: BTreeMap<String, i32>,
    labels: Vec<Labels>,
    labelled_first: BTreeMap<String, bool>,
    amounts: Vec<f32>,
}

fn watch(rx: &Receiver) -> loopback::Collecting<Seen> {
    rx.collect(Some(QUIET), Seen::default(), |seen, r| {
        if let Some(l) = &r.labels {
            seen.labels.push(l.clone());
        }
        let (Some((id, name)), Some((h, _))) = (r.stream, r.frame) else {
            return;
        };
        let first = !seen.frames.contains_key(name);
        if first {
            let labelled = seen.labels.iter().any(|l| l.layout_id == id);
            seen.labelled_first.insert(name.to_string(), labelled);
        }
        seen.ids.insert(name.to_string(), id);
        seen.frames
            .entry(name.to_string())
            .or_default()
            .push(h.frame_number);
        if let Some(s) = &r.state {
            seen.amounts.push(s.amount);
        }
    })
}

fn all(n: usize) -> Vec<i32> {
    (0..n as i32).collect()
}

#[tokio::test]
async fn two_performers_into_one_subscriber_are_told_apart_and_labelled() {
    let m = model_file(41);
    let (a, b) = (
        UdpSocket::bind("127.0.0.1:0").expect("bind"),
        UdpSocket::bind("127.0.0.1:0").expect("bind"),
    );
    let (addr_a, addr_b) = (
        a.local_addr().expect("bound"),
        b.local_addr().expect("bound"),
    );
    drop((a, b));
    let d = daemon(&m, |raw| {
        raw.performers = vec![
            daemon::serve::config::RawPerformer {
                name: "alice".into(),
                source: Some(addr_a.to_string()),
                ..Default::default()
            },
            daemon::serve::config::RawPerformer {
                name: "bob".into(),
                source: Some(addr_b.to_string()),
                ..Default::default()
            },
        ];
    })
    .await;
    let control = ControlClient::new(d.control).await.expect("client");
    let everyone = Receiver::subscribe(&control, Profile::Compact)
        .await
        .expect("sub");
    let only_bob = Receiver::subscribe_to(&control, Profile::Compact, Some("bob"))
        .await
        .expect("sub");
    let (all_seen, bob_seen) = (watch(&everyone), watch(&only_bob));
    let frames = take_frames(&m.model, 60);
    let mut alice = source_at(&addr_a.to_string(), &m, d.frames);
    let mut bob = source_at(&addr_b.to_string(), &m, d.frames);
    for n in 0..60 {
        send(&mut alice, &frames, n..n + 1).await;
        send(&mut bob, &frames, n..n + 1).await;
    }
    let (seen, seen_bob) = (
        all_seen.finish().await.expect("receiver"),
        bob_seen.finish().await.expect("receiver"),
    );
    let status = control.status().await.expect("status");
    stop(d).await;
    assert_eq!(seen.frames.get("alice"), Some(&all(60)));
    assert_eq!(seen.frames.get("bob"), Some(&all(60)));
    assert_ne!(seen.ids["alice"], seen.ids["bob"]);
    assert_eq!(
        seen.labelled_first.get("alice"),
        Some(&true),
        "labels before frames"
    );
    assert_eq!(seen.labelled_first.get("bob"), Some(&true));
    for l in &seen.labels {
        assert_eq!(
            l.names,
            m.model.labels(),
            "the output's markers, in model order"
        );
    }
    assert_eq!(seen_bob.frames.keys().collect::<Vec<_>>(), ["bob"]);
    assert_eq!(seen_bob.frames["bob"], all(60));
    let id = seen.ids["alice"];
    assert_eq!(
        loopback::text(&status, &format!("stream/{id}/name")),
        Some("alice")
    );
    assert_eq!(
        loopback::counter(&status, &format!("stream/{id}/frames")),
        Some(60)
    );
    assert_eq!(
        loopback::text(&status, "subscriber/1/performer"),
        Some("bob")
    );
    assert!(loopback::counter(&status, "subscriber/0/lease_ms").is_some_and(|ms| ms > 0));
}

/// A free loopback port (bound, then released).
#[tokio::test]
async fn a_static_receiver_that_starts_3_s_late_then_gets_every_frame() {
    let m = model_file(42);
    let port = free_port();
    let d = daemon(&m, |raw| raw.send = vec![format!("127.0.0.1:{port}")]).await;
    let frames = take_frames(&m.model, 600);
    let mut source = source_at("127.0.0.1:0", &m, d.frames);
    // 120 Hz for 5 s on a thread of its own, noting when each frame left.
    let sender = std::thread::spawn(move || {
        let start = Instant::now();
        let mut sent_at = Vec::with_capacity(frames.len());
        for (n, xyz) in frames.iter().enumerate() {
            let due = start + Duration::from_secs_f64(n as f64 / 120.0);
            std::thread::sleep(due.saturating_duration_since(Instant::now()));
            sent_at.push(Instant::now());
            source
                .send_frame(n as i32, n as i64, xyz, &[])
                .expect("finite");
        }
        sent_at
    });
    tokio::time::sleep(Duration::from_secs(3)).await;
    let late = Receiver::bind_at(([127, 0, 0, 1], port).into()).expect("the port is free");
    let started = Instant::now();
    let got = watch(&late).finish().await.expect("receiver");
    let sent_at = sender.join().expect("sender");
    let control = ControlClient::new(d.control).await.expect("client");
    let status = control.status().await.expect("status");
    stop(d).await;
    let numbers = got.frames.values().next().cloned().unwrap_or_default();
    let first = *numbers.first().expect("the late receiver gets frames") as usize;
    assert!(
        sent_at[first].duration_since(started) < Duration::from_millis(1_300),
        "the first frame came {:?} after the receiver started",
        sent_at[first].saturating_duration_since(started)
    );
    assert_eq!(
        numbers,
        (first as i32..600).collect::<Vec<_>>(),
        "every frame after it"
    );
    assert_eq!(
        loopback::counter(&status, "clients"),
        Some(1),
        "never dropped"
    );
    assert_eq!(loopback::counter(&status, "clients_dropped"), Some(0));
    assert!(loopback::counter(&status, "send_backoffs").is_some_and(|b| b >= 1));
}

#[tokio::test]
async fn an_idle_lease_expires_and_a_renewed_one_stays() {
    let m = model_file(43);
    let d = daemon(&m, |raw| raw.subscription_lease_s = Some(1.5)).await;
    let control = ControlClient::new(d.control).await.expect("client");
    let subscribe = |port| Control::Subscribe {
        port,
        profile: Profile::Compact,
        performer: None,
        cookie: None,
    };
    control
        .confirm(&subscribe(free_port()))
        .await
        .expect("idle one");
    let renewed = free_port();
    control
        .confirm(&subscribe(renewed))
        .await
        .expect("renewed one");
    assert_eq!(
        loopback::counter(&control.status().await.expect("status"), "clients"),
        Some(2)
    );
    for _ in 0..7 {
        tokio::time::sleep(Duration::from_millis(500)).await;
        control.confirm(&subscribe(renewed)).await.expect("renewal");
    }
    let status = control.status().await.expect("status");
    stop(d).await;
    assert_eq!(loopback::counter(&status, "clients"), Some(1));
    assert_eq!(
        loopback::text(&status, "subscriber/0/address"),
        Some(format!("127.0.0.1:{renewed}").as_str())
    );
}

#[tokio::test]
async fn a_spoofed_subscription_never_sends_and_a_cookie_round_trip_does() {
    let m = model_file(44);
    let d = daemon(&m, |_| {}).await;
    let frames = take_frames(&m.model, 100);
    // 127.0.0.2 stands in for a victim whose address a spoofer writes on a /subscribe.
    let victim = Receiver::bind_at("127.0.0.2:0".parse().expect("addr")).expect("bind");
    let spoofer = ControlClient::bind("127.0.0.2:0".parse().expect("addr"), d.control)
        .await
        .expect("client");
    let spoofed = Control::Subscribe {
        port: victim.addr().expect("bound").port(),
        profile: Profile::Compact,
        performer: None,
        cookie: None,
    };
    let reply = spoofer.request(&spoofed).await.expect("a reply");
    assert!(matches!(reply, Reply::Challenge(_)), "{reply:?}");
    // The real host at 127.0.0.3 answers its challenge.
    let honest = Receiver::bind_at("127.0.0.3:0".parse().expect("addr")).expect("bind");
    let client = ControlClient::bind("127.0.0.3:0".parse().expect("addr"), d.control)
        .await
        .expect("client");
    let mut ask = Control::Subscribe {
        port: honest.addr().expect("bound").port(),
        profile: Profile::Compact,
        performer: None,
        cookie: None,
    };
    let Reply::Challenge(cookie) = client.request(&ask).await.expect("a reply") else {
        panic!("a subscription from beyond 127.0.0.1 is challenged");
    };
    // Another address cannot use that cookie.
    let thief = ControlClient::bind("127.0.0.4:0".parse().expect("addr"), d.control)
        .await
        .expect("client");
    if let Control::Subscribe { cookie: c, .. } = &mut ask {
        *c = Some(cookie);
    }
    let stolen = thief.request(&ask).await.expect("a reply");
    assert!(matches!(stolen, Reply::Challenge(_)), "{stolen:?}");
    client
        .confirm(&ask)
        .await
        .expect("the echoed cookie subscribes");
    let (nothing, something) = (watch(&victim), watch(&honest));
    let mut source = source_at("127.0.0.1:0", &m, d.frames);
    send(&mut source, &frames, 0..100).await;
    let (victim_got, honest_got) = (
        nothing.finish().await.expect("receiver"),
        something.finish().await.expect("receiver"),
    );
    let status = client.status().await.expect("status");
    stop(d).await;
    assert!(
        victim_got.frames.is_empty(),
        "no frame to the spoofed address"
    );
    assert_eq!(honest_got.frames.values().next(), Some(&all(100)));
    assert_eq!(loopback::counter(&status, "clients"), Some(1));
}

#[tokio::test]
async fn control_from_a_refused_peer_or_without_the_secret_is_refused_and_frames_flow() {
    let m = model_file(45);
    let d = daemon(&m, |raw| {
        raw.control_allow = Some(vec!["127.0.0.1/32".into()]);
        raw.control_secret = Some("s3cret".into());
    })
    .await;
    let insider = ControlClient::new(d.control).await.expect("client");
    let rx = Receiver::subscribe(&insider, Profile::Compact)
        .await
        .expect("no secret needed");
    let seen = watch(&rx);
    let outsider = ControlClient::bind("127.0.0.2:0".parse().expect("addr"), d.control)
        .await
        .expect("client");
    let frames = take_frames(&m.model, 200);
    let mut source = source_at("127.0.0.1:0", &m, d.frames);
    send(&mut source, &frames, 0..100).await;
    let refused = outsider
        .request(&Control::Amount(0.5))
        .await
        .expect("a reply");
    let unsigned = insider
        .request(&Control::Amount(0.5))
        .await
        .expect("a reply");
    let signer = ControlClient::new(d.control)
        .await
        .expect("client")
        .with_secret("s3cret");
    signer
        .confirm(&Control::Amount(0.5))
        .await
        .expect("with the secret");
    send(&mut source, &frames, 100..200).await;
    let got = seen.finish().await.expect("receiver");
    let status = insider.status().await.expect("status without the secret");
    stop(d).await;
    let text = |r: &Reply| match r {
        Reply::Error { message, .. } => message.clone(),
        other => panic!("expected a refusal, got {other:?}"),
    };
    assert!(text(&refused).contains("not allowed"), "{refused:?}");
    assert!(text(&unsigned).contains("secret"), "{unsigned:?}");
    assert_eq!(loopback::counter(&status, "control_refused"), Some(2));
    assert_eq!(got.frames.values().next(), Some(&all(200)), "none lost");
}

#[tokio::test]
async fn out_of_range_values_are_refused_and_change_nothing() {
    let m = model_file(46);
    let d = daemon(&m, |_| {}).await;
    let control = ControlClient::new(d.control).await.expect("client");
    control
        .confirm(&Control::Amount(0.25))
        .await
        .expect("in range");
    let rx = Receiver::subscribe(&control, Profile::Compact)
        .await
        .expect("sub");
    let seen = watch(&rx);
    let frames = take_frames(&m.model, 120);
    let mut source = source_at("127.0.0.1:0", &m, d.frames);
    send(&mut source, &frames, 0..60).await;
    for bad in [
        Control::Amount(5.0),
        Control::Amount(-2.0),
        Control::Ramp(1e30),
        Control::Gain {
            component: 2,
            gain: 1e30,
        },
    ] {
        match control.request(&bad).await.expect("a reply") {
            Reply::Error { message, .. } => {
                assert!(message.contains("out of range"), "{bad:?}: {message}")
            }
            other => panic!("{bad:?} accepted: {other:?}"),
        }
    }
    send(&mut source, &frames, 60..120).await;
    let got = seen.finish().await.expect("receiver");
    stop(d).await;
    assert_eq!(got.frames.values().next(), Some(&all(120)));
    assert!(
        got.amounts.iter().all(|&a| (a - 0.25).abs() < 1e-6),
        "{:?}",
        got.amounts
    );
}

#[tokio::test]
async fn duplicate_labels_are_refused_with_a_reply_and_the_stream_goes_on() {
    let m = model_file(47);
    let d = daemon(&m, |_| {}).await;
    let control = ControlClient::new(d.control).await.expect("client");
    let rx = Receiver::subscribe(&control, Profile::Compact)
        .await
        .expect("sub");
    let seen = watch(&rx);
    let frames = take_frames(&m.model, 100);
    let mut source = source_at("127.0.0.1:0", &m, d.frames);
    send(&mut source, &frames, 0..50).await;
    let mut twice = labels(&m);
    twice.names[1] = twice.names[0].clone();
    let mut bad = Vec::new();
    protocol::encode_labels_into(&twice, &mut bad).expect("encodes");
    source.send_raw(&bad);
    source
        .socket()
        .set_read_timeout(Some(Duration::from_secs(1)))
        .expect("timeout");
    let mut buf = vec![0u8; 2048];
    let n = source
        .socket()
        .recv(&mut buf)
        .expect("the source hears why");
    send(&mut source, &frames, 50..100).await;
    let got = seen.finish().await.expect("receiver");
    let status = control.status().await.expect("status");
    stop(d).await;
    match protocol::decode_reply(&buf[..n]) {
        Ok(Reply::Error { message, .. }) => assert!(message.contains("named twice"), "{message}"),
        other => panic!("expected an error reply, got {other:?}"),
    }
    assert_eq!(loopback::counter(&status, "labels_refused"), Some(1));
    assert_eq!(
        got.frames.values().next(),
        Some(&all(100)),
        "the last good layout goes on"
    );
}

/// The same model with other marker names.
fn renamed(m: &ModelFile, dir: &std::path::Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string(&m.path).expect("model file");
    let mut json: serde_json::Value = serde_json::from_str(&text).expect("json");
    let labels = json
        .get_mut("labels")
        .and_then(|l| l.as_array_mut())
        .expect("a labels array");
    for (i, l) in labels.iter_mut().enumerate() {
        *l = serde_json::Value::String(format!("other{i}"));
    }
    let path = dir.join("other.json");
    std::fs::write(&path, json.to_string()).expect("writable");
    path
}

#[tokio::test]
async fn a_model_that_does_not_fit_the_running_stream_is_refused_and_nothing_sticks() {
    let m = model_file(48);
    let other = renamed(&m, m.dir.path());
    let d = daemon(&m, |_| {}).await;
    let control = ControlClient::new(d.control).await.expect("client");
    let rx = Receiver::subscribe(&control, Profile::Compact)
        .await
        .expect("sub");
    let seen = watch(&rx);
    let frames = take_frames(&m.model, 100);
    let mut source = source_at("127.0.0.1:0", &m, d.frames);
    send(&mut source, &frames, 0..50).await;
    let load = Control::ModelLoad(other.display().to_string());
    let reply = control.request(&load).await.expect("a reply");
    control
        .confirm(&Control::Amount(0.5))
        .await
        .expect("the edit still works");
    send(&mut source, &frames, 50..100).await;
    let mut newcomer = source_at("127.0.0.1:0", &m, d.frames);
    send(&mut newcomer, &frames, 0..20).await;
    let got = seen.finish().await.expect("receiver");
    let status = control.status().await.expect("status");
    stop(d).await;
    match reply {
        Reply::Error { message, .. } => {
            assert!(message.contains("does not fit"), "{message}");
            assert!(
                message.contains("other0"),
                "names the missing markers: {message}"
            );
        }
        other => panic!("a mismatched model was accepted: {other:?}"),
    }
    assert_eq!(loopback::counter(&status, "model_swaps"), Some(0));
    assert_eq!(loopback::counter(&status, "dropped_unmatched"), Some(0));
    let mut counts: Vec<usize> = got.frames.values().map(Vec::len).collect();
    counts.sort_unstable();
    assert_eq!(counts, [20, 100], "both streams, no frame lost");
}

#[tokio::test]
async fn record_start_overwrites_nothing_by_surprise() {
    let m = model_file(49);
    let d = daemon(&m, |_| {}).await;
    let control = ControlClient::new(d.control).await.expect("client");
    let existing = m.dir.path().join("take.csv");
    std::fs::write(&existing, "a user's file").expect("writable");
    let start = |path: &std::path::Path, overwrite| Control::RecordStart {
        path: path.display().to_string(),
        raw: None,
        overwrite,
    };
    let refused = control
        .request(&start(&existing, false))
        .await
        .expect("a reply");
    assert_eq!(
        std::fs::read_to_string(&existing).expect("kept"),
        "a user's file"
    );
    control
        .confirm(&start(&existing, true))
        .await
        .expect("asked to overwrite");
    let again = control
        .request(&start(&existing, true))
        .await
        .expect("a reply");
    let next = m.dir.path().join("next.csv");
    control
        .confirm(&start(&next, false))
        .await
        .expect("a new path switches");
    control.confirm(&Control::RecordStop).await.expect("stops");
    stop(d).await;
    let message = |r: &Reply| match r {
        Reply::Error { message, .. } => message.clone(),
        other => panic!("expected a refusal, got {other:?}"),
    };
    assert!(message(&refused).contains("exists"), "{refused:?}");
    assert!(message(&again).contains("already recording"), "{again:?}");
}
