//! `emoshift replay` on loopback: every frame arrives once, in order, decoded exactly, after
//! the labels.
#![allow(clippy::unwrap_used)] // a failed unwrap is a failed test

use std::net::UdpSocket;
use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use protocol::{decode_frame_into, decode_labels, messages, Address, FrameBuf, FrameForm, Limits};
use replay::Take;

/// 30 frames at 120 Hz, numbered from 5, three markers with gaps.
fn small_take() -> Take {
    let labels = vec!["Chin".into(), "Lip_Upper".into(), "Nose".into()];
    let mut take = Take::new(labels, 120.0, 5);
    for f in 0..30 {
        let t = f as f32;
        let xyz = [
            t,
            2.5 * t,
            -3.0,
            100.125,
            -t * 0.01,
            7.0,
            1e-3,
            0.5,
            1234.5678 + t,
        ];
        take.push_frame(&xyz, &[false, f % 4 == 1, (10..13).contains(&f)]);
    }
    take
}

/// What the receiver saw: label layouts and frames (frame number, capture time, form, take
/// data) in arrival order.
#[derive(Default)]
struct Received {
    first_is_labels: Option<bool>,
    labels: Vec<(i32, Vec<String>)>,
    frames: Vec<GotFrame>,
}

/// One decoded frame.
struct GotFrame {
    number: i32,
    time_us: i64,
    form: FrameForm,
    xyz: Vec<f32>,
    missing: Vec<bool>,
}

/// Runs `emoshift replay` against a socket on 127.0.0.1:0 and collects every datagram.
fn replay_into_socket(file: &Path, extra: &[&str]) -> (Output, Received) {
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    socket
        .set_read_timeout(Some(Duration::from_millis(50)))
        .unwrap();
    let to = socket.local_addr().unwrap().to_string();
    let mut child = Command::new(env!("CARGO_BIN_EXE_emoshift"))
        .args([
            "replay",
            file.to_str().unwrap(),
            "--to",
            &to,
            "--speed",
            "4",
        ])
        .args(extra)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut got = Received::default();
    let mut buf = vec![0u8; 65_536];
    let mut frame = FrameBuf::new();
    let deadline = Instant::now() + Duration::from_secs(20);
    let mut exited_at = None;
    // Drain until the sender has exited and the socket stayed quiet once more.
    loop {
        match socket.recv(&mut buf) {
            Ok(n) => collect(&buf[..n], &mut got, &mut frame),
            Err(_) if exited_at.is_some() => break,
            Err(_) => {}
        }
        if exited_at.is_none() && child.try_wait().unwrap().is_some() {
            exited_at = Some(Instant::now());
        }
        assert!(Instant::now() < deadline, "emoshift replay did not finish");
    }
    (child.wait_with_output().unwrap(), got)
}

fn collect(datagram: &[u8], got: &mut Received, frame: &mut FrameBuf) {
    for msg in messages(datagram, &Limits::default()).unwrap() {
        let address = Address::parse(msg.address);
        got.first_is_labels
            .get_or_insert(address == Some(Address::Labels));
        match address {
            Some(Address::Labels) => {
                let l = decode_labels(msg.bytes).unwrap();
                got.labels.push((l.layout_id, l.names));
            }
            Some(Address::Frame) => {
                let h = decode_frame_into(msg.bytes, frame).unwrap();
                let missing: Vec<bool> = (0..h.marker_count).map(|m| frame.is_missing(m)).collect();
                got.frames.push(GotFrame {
                    number: h.frame_number,
                    time_us: h.capture_time_us,
                    form: h.form,
                    xyz: frame.positions().to_vec(),
                    missing,
                });
            }
            other => panic!("unexpected message {other:?}"),
        }
    }
}

/// Checks the frames are take indices `first..` in order, each once, exact.
fn assert_frames(take: &Take, got: &Received, first: usize, form: FrameForm) {
    assert_eq!(
        got.frames.len(),
        take.n_frames() - first,
        "every frame, once"
    );
    for (k, got) in got.frames.iter().enumerate() {
        let i = first + k;
        assert_eq!(got.number as i64, take.first_frame + i as i64, "in order");
        assert_eq!(got.time_us, (i as f64 * 1e6 / 120.0).round() as i64);
        assert_eq!(got.form, form);
        assert_eq!(
            got.missing.as_slice(),
            take.frame_missing(i),
            "frame index {i}"
        );
        for m in 0..take.n_markers() {
            let p = &got.xyz[m * 3..m * 3 + 3];
            match take.sample(i, m) {
                Some(want) => assert_eq!(p, want, "frame index {i} marker {m}"),
                None => assert!(p.iter().all(|v| v.is_nan())),
            }
        }
    }
}

#[test]
fn replay_sends_labels_then_every_frame_in_order() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("small.trc");
    let take = small_take();
    replay::save(&file, &take).unwrap();

    let (out, got) = replay_into_socket(&file, &["--layout-id", "3"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(got.first_is_labels, Some(true), "labels come first");
    assert_eq!(got.labels[0], (3, take.labels.clone()));
    assert_frames(&take, &got, 0, FrameForm::Blob);
    assert!(stdout.contains("sent 30 frames"), "{stdout}");
    assert!(stdout.contains("late sends:"), "{stdout}");
}

#[test]
fn replay_flat_from_a_start_frame() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("small.csv");
    let take = small_take();
    replay::save(&file, &take).unwrap();

    let (out, got) = replay_into_socket(&file, &["--format", "flat", "--start-frame", "20"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(got.first_is_labels, Some(true));
    assert_frames(&take, &got, 20, FrameForm::Flat);
}

#[test]
fn bad_options_are_usage_errors() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("small.csv");
    replay::save(&file, &small_take()).unwrap();
    let f = file.to_str().unwrap();
    for extra in [
        &["--speed", "0"][..],
        &["--start-frame", "30"],
        &["--to", "no-port-here"],
    ] {
        let mut args = vec!["replay", f];
        if extra[0] != "--to" {
            args.extend(["--to", "127.0.0.1:9"]);
        }
        args.extend(extra);
        let out = Command::new(env!("CARGO_BIN_EXE_emoshift"))
            .args(&args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "one line: {stderr}");
    }
}
