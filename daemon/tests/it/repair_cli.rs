//! Issue 36 from the command line: `info` and `convert` warn about a take cut off by a crash
//! and name the fix, `repair` recovers it in place or to `--out`. The files are the ones main's
//! old recorder left when killed (replay/tests/fixtures/SOURCE.md).

use std::path::{Path, PathBuf};

use crate::common::{ok, p, run};

/// A copy of a replay fixture in `dir` (the tests change it).
fn killed(dir: &Path, ext: &str) -> PathBuf {
    let from = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../replay/tests/fixtures")
        .join(format!("killed-before-issue-36.{ext}"));
    let to = dir.join(format!("live.{ext}"));
    std::fs::copy(&from, &to).expect("fixture copies");
    to
}

#[test]
fn issue_36_info_warns_of_frames_past_the_header_and_names_repair() {
    let dir = tempfile::tempdir().expect("temp dir");
    for (ext, holds, header) in [("c3d", 200, 1), ("trc", 116, 0)] {
        let file = killed(dir.path(), ext);
        let want = format!(
            "holds {holds} frames, header says {header}: run `emoshift repair {}`",
            file.display()
        );
        if header > 0 {
            let printed = ok(&["info", p(&file)]);
            assert!(printed.contains(&format!("warning:  {want}")), "{printed}");
            assert!(printed.contains("frames:   1"), "{printed}");
            let json = ok(&["info", p(&file), "--json"]);
            let v: serde_json::Value = serde_json::from_str(&json).expect("json");
            assert_eq!(v["warnings"][0], want.as_str(), "{json}");
        } else {
            // Nothing counted: the take cannot be read at all, and the error says why and what to do.
            let out = run(&["info", p(&file)]);
            let err = String::from_utf8_lossy(&out.stderr);
            assert!(!out.status.success());
            assert!(err.contains(&want), "{err}");
        }
    }
}

#[test]
fn issue_36_repair_recovers_every_frame_in_place_or_to_out() {
    let dir = tempfile::tempdir().expect("temp dir");
    for (ext, holds) in [("c3d", 200), ("trc", 116)] {
        let file = killed(dir.path(), ext);
        let before = std::fs::read(&file).expect("reads");
        let out = dir.path().join(format!("fixed.{ext}"));
        let printed = ok(&["repair", p(&file), "--out", p(&out)]);
        let said = format!("{holds} frames (its header said");
        assert!(
            printed.contains("repaired") && printed.contains(&said),
            "{printed}"
        );
        assert_eq!(
            std::fs::read(&file).expect("reads"),
            before,
            "--out leaves FILE alone"
        );
        assert_eq!(
            replay::load(&out).expect("repaired reads").n_frames(),
            holds
        );

        let printed = ok(&["repair", p(&file)]);
        assert!(printed.contains(&said), "{printed}");
        assert_eq!(replay::load(&file).expect("reads").n_frames(), holds);
        let info = ok(&["info", p(&file)]);
        assert!(!info.contains("warning"), "{info}");
        let again = ok(&["repair", p(&file)]);
        assert!(again.contains("nothing to repair"), "{again}");
    }
}

#[test]
fn issue_36_repair_keeps_the_format_and_asks_before_overwriting() {
    let dir = tempfile::tempdir().expect("temp dir");
    let file = killed(dir.path(), "c3d");
    let trc = dir.path().join("x.trc");
    let out = run(&["repair", p(&file), "--out", p(&trc)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("emoshift convert"), "{err}");

    let existing = dir.path().join("exists.c3d");
    std::fs::write(&existing, b"mine").expect("writes");
    let out = run(&["repair", p(&file), "--out", p(&existing)]);
    assert!(!out.status.success());
    assert_eq!(std::fs::read(&existing).expect("reads"), b"mine");
    ok(&["repair", p(&file), "--out", p(&existing), "--force"]);
    assert_eq!(replay::load(&existing).expect("reads").n_frames(), 200);
}

#[test]
fn issue_36_convert_warns_that_it_converts_only_the_counted_frames() {
    let dir = tempfile::tempdir().expect("temp dir");
    let file = killed(dir.path(), "c3d");
    let out = dir.path().join("x.csv");
    let printed = ok(&["convert", p(&file), p(&out)]);
    assert!(
        printed.contains("holds 200 frames, header says 1: run `emoshift repair"),
        "{printed}"
    );
}
