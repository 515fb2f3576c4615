//! Issue 37, the first hour on a stage: a NatNet name mismatch in `serve` warns, naming both
//! sides and the flag that fixes it; a wrong `--performer` in `record` says which marker sets
//! the server has, and exits non-zero when nothing was written; `record` shows its progress.

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use super::natnet::{motive, send_osc, stream};
use super::support::*;

/// Lines of `child`'s stderr, each with when it came, gathered on a thread.
fn stderr_lines(child: &mut Child) -> Arc<Mutex<Vec<(Instant, String)>>> {
    let lines = Arc::new(Mutex::new(Vec::new()));
    let err = child.stderr.take().expect("stderr piped");
    let into = Arc::clone(&lines);
    std::thread::spawn(move || {
        for line in BufReader::new(err).lines().map_while(Result::ok) {
            into.lock().expect("lines").push((Instant::now(), line));
        }
    });
    lines
}

fn signal(child: &Child, sig: &str) {
    let kill = Command::new("kill")
        .args([sig, &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(kill.success());
}

fn text(lines: &Mutex<Vec<(Instant, String)>>) -> String {
    let lines = lines.lock().expect("lines");
    lines.iter().map(|(_, l)| format!("{l}\n")).collect()
}

/// Motive names the markers `Face:<marker>`, the model knows `<marker>`: `serve` says so at
/// WARN with both sides' names and the flag to pass.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_natnet_name_mismatch_in_serve_warns_with_both_sides_and_the_fix() {
    let m = model_file(37);
    let mut server = motive(&m, "127.0.0.1:0".parse().expect("addr"), None);
    let mut child = Command::new(env!("CARGO_BIN_EXE_emoshift-e2e"))
        .arg("serve")
        .arg("--model")
        .arg(&m.path)
        .args(["--listen", "127.0.0.1:0", "--control", "127.0.0.1:0"])
        .args(["--natnet", &server.command_addr().to_string()])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary starts");
    let lines = stderr_lines(&mut child);
    for _ in 0..100 {
        if server.clients() > 0 {
            break;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    tokio::time::sleep(Duration::from_millis(500)).await;
    stream(&m, &mut server, 0..120).await;
    tokio::time::sleep(Duration::from_millis(300)).await;
    signal(&child, "-TERM");
    let _ = tokio::task::spawn_blocking(move || child.wait()).await;
    server.stop();
    let err = text(&lines);
    let warn = err
        .lines()
        .find(|l| l.contains("WARN") && l.contains("--natnet-names marker"))
        .unwrap_or_else(|| panic!("no WARN suggesting --natnet-names marker in:\n{err}"));
    let first = &m.model.labels()[0];
    assert!(
        warn.contains(&format!("Face:{first}")),
        "the source's names: {warn}"
    );
    assert!(
        warn.contains("whose markers start"),
        "the model's names: {warn}"
    );
}

/// `record --natnet --performer face` while the server streams `Face`: told within two
/// seconds of the first frame, and a non-zero exit with nothing written after Ctrl-C.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_wrong_performer_is_named_at_once_and_exits_non_zero() {
    let m = model_file(38);
    let mut server = motive(&m, "127.0.0.1:0".parse().expect("addr"), None);
    let out = m.dir.path().join("face.c3d");
    let mut child = Command::new(env!("CARGO_BIN_EXE_emoshift-e2e"))
        .args(["record", "--natnet", &server.command_addr().to_string()])
        .args(["--natnet-names", "marker", "--performer", "face", "--out"])
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary starts");
    let lines = stderr_lines(&mut child);
    for _ in 0..100 {
        if server.clients() > 0 {
            break;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    tokio::time::sleep(Duration::from_millis(500)).await;
    let first_frame = Instant::now();
    stream(&m, &mut server, 0..300).await;
    signal(&child, "-INT");
    let done = tokio::task::spawn_blocking(move || child.wait())
        .await
        .expect("join")
        .expect("the child ends");
    server.stop();
    let want = "no marker set 'face'; the server has: Face";
    let told = lines
        .lock()
        .expect("lines")
        .iter()
        .find(|(_, l)| l.contains(want))
        .map(|(at, _)| at.duration_since(first_frame));
    let err = text(&lines);
    let told = told.unwrap_or_else(|| panic!("no {want:?} in:\n{err}"));
    assert!(told < Duration::from_secs(2), "told after {told:?}");
    assert!(!done.success(), "exit status {done:?}:\n{err}");
    assert!(!out.exists(), "nothing is written");
}

/// `record` shows how the take goes while it records (frames, rate, gaps, time), as `train`
/// shows its steps: here in a pipe, with a line for every advance.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn record_shows_frames_rate_gaps_and_time_while_it_records() {
    let m = model_file(39);
    let port = free_port();
    let out = m.dir.path().join("take.csv");
    let child = Command::new(env!("CARGO_BIN_EXE_emoshift-e2e"))
        .args(["record", "--listen", &format!("127.0.0.1:{port}")])
        .args(["--frames", "100", "--out"])
        .arg(&out)
        .env("EMOSHIFT_PROGRESS_SECS", "0")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary starts");
    tokio::time::sleep(Duration::from_millis(500)).await;
    let to = format!("127.0.0.1:{port}").parse().expect("addr");
    send_osc(&m, to, 0..110).await;
    let done = tokio::task::spawn_blocking(move || child.wait_with_output())
        .await
        .expect("join")
        .expect("the child ends by itself after 100 frames");
    let err = String::from_utf8_lossy(&done.stderr);
    assert!(done.status.success(), "{err}");
    let line = err
        .lines()
        .find(|l| l.starts_with("record: recording ") && l.contains(" Hz, 0 gaps, "))
        .unwrap_or_else(|| panic!("no progress line with rate, gaps and time in:\n{err}"));
    assert!(line.contains("frames"), "{line}");
}
