//! The binary under SIGTERM: exits 0 within 1 s with the recording complete.

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use protocol::{Control, Reply};

use super::support::*;

fn free_port() -> u16 {
    std::net::UdpSocket::bind("127.0.0.1:0")
        .and_then(|s| s.local_addr())
        .expect("an ephemeral port")
        .port()
}

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
    let start = Control::RecordStart(out.display().to_string());
    // The child needs a moment to bind: retry the first control until it answers.
    let mut reply = None;
    for _ in 0..50 {
        let attempt = tokio::time::timeout(Duration::from_millis(200), control.send(&start));
        if let Ok(r) = attempt.await {
            reply = Some(r);
            break;
        }
    }
    assert!(matches!(reply, Some(Reply::Confirm(_))), "{reply:?}");
    let frames = take_frames(&m.model, 90);
    let mut source = Source::new(format!("127.0.0.1:{fp}").parse().expect("addr"), &m.model).await;
    for (n, xyz) in frames.iter().enumerate() {
        source.frame(n as i32, xyz).await;
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
}
