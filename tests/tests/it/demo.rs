//! `emoshift demo`, the README's first command: the whole chain runs, the client receives the
//! edited stream, the sweep reaches every emotion, and the kept session, model and report are
//! there.

use std::process::Command;

#[test]
fn the_demo_runs_the_whole_chain_and_keeps_what_it_was_asked_to() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let keep = dir.path().join("demo");
    let out = Command::new(env!("CARGO_BIN_EXE_emoshift-e2e"))
        .arg("demo")
        .arg("--keep")
        .arg(&keep)
        .output()
        .expect("emoshift demo runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "demo failed:\n{stdout}\n{stderr}");
    let frames = stdout
        .lines()
        .find_map(|l| l.strip_prefix("frames: "))
        .unwrap_or_else(|| panic!("no frames line:\n{stdout}"));
    let numbers: Vec<usize> = frames
        .split_whitespace()
        .filter_map(|w| w.parse().ok())
        .collect();
    let (sent, received) = (numbers[0], numbers[2]);
    assert!(sent >= 1_000, "{frames}");
    assert!(received * 10 >= sent * 9, "most frames arrive: {frames}");
    for target in ["sad", "happy", "angry"] {
        let windows = stdout
            .lines()
            .filter(|l| l.contains(&format!("target {target} ")))
            .count();
        assert!(windows >= 4, "the sweep spent 4 s on {target}:\n{stdout}");
    }
    for kept in ["model.json", "report/report.html", "session/session.toml"] {
        assert!(keep.join(kept).is_file(), "{kept} kept:\n{stdout}");
    }
}
