//! Issue 36: a take killed with SIGKILL mid-recording reads with every frame but at most the
//! last second (120 frames at 120 Hz), from `serve` (`/record/start`, edited and raw) and from
//! `record`, in C3D, TRC and CSV; a power cut loses no more, since the header counts only
//! frames already synced (replay's `durable` module).

use std::net::SocketAddr;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use daemon::loopback;
use protocol::{Control, Labels, Reply};

use super::support::*;

/// Frames sent before the kill: 3 s at 120 Hz.
const SENT: usize = 360;
/// Frames a kill may cost: the last second.
const MAY_LOSE: usize = 120;

/// Sends `frames` at 120 Hz from a loopback source naming the model's markers.
async fn stream_at_120_hz(model: &ica_core::model::IcaModel, to: SocketAddr, frames: &[Vec<f32>]) {
    let labels = Labels {
        layout_id: 0,
        names: model.labels().to_vec(),
    };
    let mut source = loopback::Source::on_loopback(&labels, to).expect("a loopback source");
    let mut tick = tokio::time::interval(Duration::from_secs_f64(1.0 / 120.0));
    for (n, xyz) in frames.iter().enumerate() {
        tick.tick().await;
        source
            .send_frame(n as i32, n as i64 * 8_333, xyz, &[])
            .expect("finite");
    }
}

fn sigkill(child: &mut Child) {
    let status = Command::new("kill")
        .args(["-KILL", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(status.success());
    child.wait().expect("the child is reaped");
}

/// The take reads, holds a prefix of what was sent missing at most the last second, and its
/// samples are the ones sent (when `sent` is given: the raw input, not the edited stream).
fn check_killed(path: &Path, sent: Option<&[Vec<f32>]>) {
    let take = replay::load(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let n = take.n_frames();
    assert!(
        (SENT - MAY_LOSE..=SENT).contains(&n),
        "{}: {n} of {SENT} frames",
        path.display()
    );
    if let Some(sent) = sent {
        for (f, want) in sent.iter().take(n).enumerate() {
            let got = &take.positions[f * want.len()..(f + 1) * want.len()];
            let worst = got
                .iter()
                .zip(want)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0f32, f32::max);
            assert!(worst < 1e-3, "{}: frame {f} off by {worst}", path.display());
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn issue_36_serve_recording_killed_after_3_s_keeps_all_but_the_last_second() {
    let m = model_file(36);
    let frames = take_frames(&m.model, SENT);
    for (edited, raw) in [
        ("live.c3d", "input.trc"),
        ("live.trc", "input.csv"),
        ("live.csv", "input.c3d"),
    ] {
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
        let (out, raw_out) = (m.dir.path().join(edited), m.dir.path().join(raw));
        let start = Control::RecordStart {
            path: out.display().to_string(),
            raw: Some(raw_out.display().to_string()),
            overwrite: false,
        };
        let reply = control.send_when_up(&start).await;
        assert!(matches!(reply, Some(Reply::Confirm(_))), "{reply:?}");
        stream_at_120_hz(
            &m.model,
            format!("127.0.0.1:{fp}").parse().expect("addr"),
            &frames,
        )
        .await;
        sigkill(&mut child);
        check_killed(&out, None);
        check_killed(&raw_out, Some(&frames));
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn issue_36_record_killed_after_3_s_keeps_all_but_the_last_second() {
    let m = model_file(37);
    let frames = take_frames(&m.model, SENT);
    for ext in ["c3d", "trc", "csv"] {
        let port = free_port();
        let out = m.dir.path().join(format!("take.{ext}"));
        let mut child = Command::new(env!("CARGO_BIN_EXE_emoshift-e2e"))
            .args(["record", "--listen", &format!("127.0.0.1:{port}"), "--out"])
            .arg(&out)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("the binary starts");
        // Time to bind.
        tokio::time::sleep(Duration::from_millis(300)).await;
        let to = format!("127.0.0.1:{port}").parse().expect("addr");
        stream_at_120_hz(&m.model, to, &frames).await;
        sigkill(&mut child);
        check_killed(&out, Some(&frames));
    }
}

/// A tmpfs of `size` mounted on a temporary folder for the test's life (needs root, as CI
/// runs). `None` when it cannot be mounted outside CI (said on stderr); in CI that fails.
pub struct Tmpfs {
    dir: tempfile::TempDir,
}

impl Tmpfs {
    pub fn mount(size: &str) -> Option<Tmpfs> {
        let dir = tempfile::tempdir().expect("temp dir");
        let mounted = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(dir.path())
            .stderr(Stdio::piped())
            .output()
            .expect("mount runs");
        if mounted.status.success() {
            return Some(Tmpfs { dir });
        }
        let why = String::from_utf8_lossy(&mounted.stderr);
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "CI must be able to mount a tmpfs (run as root): {why}"
        );
        eprintln!("not tested: mounting a tmpfs needs root ({why})");
        None
    }

    pub fn path(&self) -> &Path {
        self.dir.path()
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(self.dir.path()).status();
    }
}

/// "stopped after N frames": N.
pub fn frames_kept(message: &str) -> usize {
    let after = message
        .split("stopped after ")
        .nth(1)
        .unwrap_or_else(|| panic!("no frame count in {message:?}"));
    after
        .split(' ')
        .next()
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no frame count in {message:?}"))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn issue_36_record_on_a_full_disk_exits_1_naming_the_cause_and_keeps_its_frames() {
    let Some(disk) = Tmpfs::mount("64k") else {
        return;
    };
    let m = model_file(38);
    // About 8 s at 120 Hz: far more than 64 KiB holds in any format.
    let frames = take_frames(&m.model, 1_000);
    for ext in ["c3d", "trc", "csv"] {
        let port = free_port();
        let out = disk.path().join(format!("take.{ext}"));
        let child = Command::new(env!("CARGO_BIN_EXE_emoshift-e2e"))
            .args(["record", "--listen", &format!("127.0.0.1:{port}"), "--out"])
            .arg(&out)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("the binary starts");
        tokio::time::sleep(Duration::from_millis(300)).await;
        let to = format!("127.0.0.1:{port}").parse().expect("addr");
        let sender = tokio::spawn({
            let model = m.model.clone();
            let frames = frames.clone();
            async move { stream_at_120_hz(&model, to, &frames).await }
        });
        let done = tokio::task::spawn_blocking(move || child.wait_with_output())
            .await
            .expect("join")
            .expect("record ends by itself when the disk is full");
        sender.abort();
        let err = String::from_utf8_lossy(&done.stderr);
        assert_eq!(done.status.code(), Some(1), "{ext}: {err}");
        assert!(err.contains("No space left on device"), "{ext}: {err}");
        let kept = frames_kept(&err);
        let take = replay::load(&out).unwrap_or_else(|e| panic!("{ext}: {e}; {err}"));
        assert!(kept > 0, "{ext}: {err}");
        assert_eq!(take.n_frames(), kept, "{ext}: {err}");
        std::fs::remove_file(&out).expect("room for the next format");
    }
}

/// The next datagram the daemon sends `socket`, decoded.
async fn next_reply(socket: &tokio::net::UdpSocket) -> Reply {
    let mut buf = vec![0; protocol::MAX_UDP_PAYLOAD];
    let (n, _) = tokio::time::timeout(Duration::from_secs(5), socket.recv_from(&mut buf))
        .await
        .expect("a reply within 5 s")
        .expect("recv");
    protocol::decode_reply(&buf[..n]).expect("a reply")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn issue_36_serve_recording_on_a_full_disk_stops_with_its_cause_and_the_stream_goes_on() {
    let Some(disk) = Tmpfs::mount("64k") else {
        return;
    };
    let m = model_file(39);
    let d = start(&m.path, Vec::new()).await;
    let control = ControlClient::new(d.control).await;
    let rx = Receiver::subscribe(&control, protocol::Profile::Compact).await;
    let collect = rx.spawn_frames(Duration::from_millis(500));
    // The controller that starts the recording hears why it stopped, later, unasked.
    let controller = tokio::net::UdpSocket::bind("127.0.0.1:0")
        .await
        .expect("bind");
    let (out, raw_out) = (disk.path().join("live.c3d"), disk.path().join("input.trc"));
    let mut bytes = Vec::new();
    protocol::encode_control_into(
        &Control::RecordStart {
            path: out.display().to_string(),
            raw: Some(raw_out.display().to_string()),
            overwrite: false,
        },
        &mut bytes,
    );
    controller.send_to(&bytes, d.control).await.expect("send");
    let confirmed = next_reply(&controller).await;
    assert!(matches!(confirmed, Reply::Confirm(_)), "{confirmed:?}");

    // 4 s at 120 Hz: 64 KiB holds a fraction of it.
    let frames = take_frames(&m.model, 480);
    stream_at_120_hz(&m.model, d.frames, &frames).await;
    let got = collect.await.expect("join");
    assert_eq!(got.len(), frames.len(), "the stream lost frames");

    let why = match next_reply(&controller).await {
        Reply::Error { address, message } => {
            assert_eq!(address, "/record/start");
            message
        }
        other => panic!("expected /emoshift/error, got {other:?}"),
    };
    assert!(why.contains("No space left on device"), "{why}");
    let status = match control.send(&Control::Status).await {
        Reply::Status(pairs) => pairs,
        other => panic!("{other:?}"),
    };
    assert_eq!(loopback::text(&status, "recording"), Some(""), "{status:?}");
    let error = loopback::text(&status, "recording_error").expect("recording_error");
    assert_eq!(error, why);
    // Both files closed valid with the frames that fit (the first to fill stopped both).
    let edited = replay::load(&out).expect("the edited take reads");
    let raw = replay::load(&raw_out).expect("the raw take reads");
    assert!(edited.n_frames() > 0 && raw.n_frames() > 0);
    assert!(edited.n_frames() < frames.len() && raw.n_frames() < frames.len());
    assert!(
        why.contains(&format!("stopped after {} frames", edited.n_frames()))
            || why.contains(&format!("stopped after {} frames", raw.n_frames())),
        "{why}: edited {}, raw {}",
        edited.n_frames(),
        raw.n_frames()
    );
    d.stop().await;
}
