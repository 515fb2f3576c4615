//! The binary under SIGTERM: exits 0 within 1 s with the recordings (edited and raw input)
//! complete.

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use protocol::{encode_frame_into, encode_labels_into, Control, FrameBuf, Labels, Reply};

use super::support::*;

#[tokio::test]
async fn a_recording_is_complete_after_sigterm() {
    let m = model_file(31);
    let (fp, cp) = (free_port(), free_port());
    let mut child = Command::new(env!("CARGO_BIN_EXE_emoshift-e2e"))
        .args(["serve", "--model"])
        .arg(&m.path)
        .args(["--listen", &format!("127.0.0.1:{fp}")])
        .args(["--control", &format!("127.0.0.1:{cp}")])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("the binary starts");
    let control = ControlClient::new(format!("127.0.0.1:{cp}").parse().expect("addr")).await;
    let out = m.dir.path().join("live.csv");
    let raw_out = m.dir.path().join("input.trc");
    let start = Control::RecordStart {
        path: out.display().to_string(),
        raw: Some(raw_out.display().to_string()),
        overwrite: false,
    };
    // The child needs a moment to bind: retry the first control until it answers.
    let reply = control.send_when_up(&start).await;
    assert!(matches!(reply, Some(Reply::Confirm(_))), "{reply:?}");
    let sent = stage_frames(&m.model, 90);
    let source = Source::new(format!("127.0.0.1:{fp}").parse().expect("addr"), &m.model).await;
    source.raw(&sent.labels_datagram).await;
    for (n, d) in sent.datagrams.iter().enumerate() {
        source.raw(d).await;
        if n % 8 == 7 {
            tokio::time::sleep(Duration::from_millis(1)).await;
        }
    }
    tokio::time::sleep(Duration::from_millis(200)).await;
    let t = Instant::now();
    let status = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(status.success());
    let exit = loop {
        if let Some(s) = child.try_wait().expect("wait") {
            break s;
        }
        assert!(
            t.elapsed() < Duration::from_secs(1),
            "still running 1 s after SIGTERM"
        );
        std::thread::sleep(Duration::from_millis(10));
    };
    assert!(exit.success(), "exit status {exit:?}");
    let take = replay::load(&out).expect("the recording loads");
    assert_eq!(take.n_frames(), 90);
    assert_eq!(take.labels, m.model.labels());
    assert!(take.missing.iter().all(|&m| !m), "the model fills the gaps");
    let raw = replay::load(&raw_out).expect("the raw recording loads");
    assert_eq!(
        raw.labels, sent.take.labels,
        "the source's own labels and order"
    );
    assert_eq!(raw.n_frames(), 90);
    assert_eq!(raw.missing, sent.take.missing, "the source's gaps");
    for (i, (a, b)) in raw.positions.iter().zip(&sent.take.positions).enumerate() {
        if !raw.missing[i / 3] {
            // TRC keeps the shortest text of each f32: exact.
            assert_eq!(a, b, "sample {i}");
        }
    }
}

/// What a stage sends: the model's markers in reverse order plus a prop marker the model
/// does not know, the first marker missing every 10th frame.
struct Sent {
    labels_datagram: Vec<u8>,
    datagrams: Vec<Vec<u8>>,
    take: replay::Take,
}

fn stage_frames(model: &ica_core::model::IcaModel, n: usize) -> Sent {
    let mut labels: Vec<String> = model.labels().iter().rev().cloned().collect();
    labels.push("prop".into());
    let mut labels_datagram = Vec::new();
    encode_labels_into(
        &Labels {
            layout_id: 0,
            names: labels.clone(),
        },
        &mut labels_datagram,
    )
    .expect("labels");
    let markers = labels.len();
    let mut take = replay::Take::new(labels, model.rate_hz(), 0);
    let mut buf = FrameBuf::with_max_markers(markers);
    let mut datagrams = Vec::with_capacity(n);
    for (f, xyz) in take_frames(model, n).iter().enumerate() {
        let mut frame: Vec<f32> = xyz.chunks(3).rev().flatten().copied().collect();
        frame.extend([10.0 + f as f32, -20.5, 333.25]);
        let mut gaps = vec![false; markers];
        gaps[0] = f % 10 == 0;
        buf.set_frame(f as i32, f as i64, &frame).expect("finite");
        buf.set_missing(0, gaps[0]);
        let mut d = Vec::new();
        encode_frame_into(&buf, &mut d).expect("finite");
        datagrams.push(d);
        take.push_frame(&frame, &gaps);
    }
    Sent {
        labels_datagram,
        datagrams,
        take,
    }
}

/// The child's peak resident memory, kB.
fn peak_rss_kb(pid: u32) -> u64 {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).expect("proc status");
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .expect("VmHWM")
}

#[tokio::test]
async fn model_load_of_a_device_or_a_fifo_is_answered_at_once_and_sigterm_still_exits() {
    let m = model_file(32);
    let fifo = m.dir.path().join("model.fifo");
    let made = Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo runs");
    assert!(made.success());
    let (fp, cp) = (free_port(), free_port());
    let mut child = Command::new(env!("CARGO_BIN_EXE_emoshift-e2e"))
        .args(["serve", "--model"])
        .arg(&m.path)
        .args(["--listen", &format!("127.0.0.1:{fp}")])
        .args(["--control", &format!("127.0.0.1:{cp}")])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("the binary starts");
    let control = ControlClient::new(format!("127.0.0.1:{cp}").parse().expect("addr")).await;
    let up = control.send_when_up(&Control::Status).await.is_some();
    assert!(up, "the daemon answers /status");
    for path in ["/dev/zero".into(), fifo.display().to_string()] {
        let t = Instant::now();
        let reply = tokio::time::timeout(
            Duration::from_secs(1),
            control.send(&Control::ModelLoad(path.clone())),
        )
        .await
        .unwrap_or_else(|_| panic!("/model/load {path} answered within 1 s"));
        match reply {
            Reply::Error { message, .. } => {
                assert!(message.contains("not a regular file"), "{path}: {message}")
            }
            other => panic!("/model/load {path}: {other:?}"),
        }
        assert!(t.elapsed() < Duration::from_secs(1));
    }
    let peak = peak_rss_kb(child.id());
    assert!(peak < 200_000, "peak RSS {peak} kB");
    let t = Instant::now();
    let status = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(status.success());
    let exit = loop {
        if let Some(s) = child.try_wait().expect("wait") {
            break s;
        }
        assert!(
            t.elapsed() < Duration::from_secs(1),
            "still running 1 s after SIGTERM"
        );
        std::thread::sleep(Duration::from_millis(10));
    };
    assert!(exit.success(), "exit status {exit:?}");
}
