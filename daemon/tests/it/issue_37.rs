//! Issue 37, the first hour on a stage: what a newcomer met, pinned from the command line.

use daemon::offline::analysis::MIN_SENTENCES_PER_EMOTION;

use crate::common::{ok, p};

/// A session of 3 sentences in 3 emotions: `analyze` says on the terminal what the session
/// lacks, with the number of sentences to record; its one emotion direction is drawn as a line.
#[test]
fn analyze_on_a_small_session_advises_more_sentences() {
    let dir = tempfile::tempdir().expect("temp dir");
    let session = dir.path().join("s");
    ok(&[
        "synth",
        "--out",
        p(&session),
        "--seed",
        "3",
        "--sentences",
        "3",
        "--emotions",
        "neutral,happy,angry",
        "--emotion-dims",
        "1",
    ]);
    let manifest = session.join("session.toml");
    let model = dir.path().join("model.json");
    ok(&["train", "--manifest", p(&manifest), "--out", p(&model)]);
    let out = ok(&[
        "analyze",
        "--model",
        p(&model),
        "--manifest",
        p(&manifest),
        "--out",
        p(&dir.path().join("report")),
    ]);
    let advice = format!(
        "warning: record at least {MIN_SENTENCES_PER_EMOTION} sentences per emotion; you have 3"
    );
    assert!(out.contains(&advice), "no {advice:?} in:\n{out}");
    let html = std::fs::read_to_string(dir.path().join("report/report.html")).expect("report");
    assert!(html.contains("What the session lacks"), "{html}");
    // One emotion direction: the map is a line with its axis, not an empty plane.
    let map = std::fs::read_to_string(dir.path().join("report/emotion_map.svg")).expect("map");
    assert!(
        map.contains("along the one emotion direction") && map.contains("class=\"axis\""),
        "{map}"
    );
    assert_eq!(
        map.matches("class=\"take\"").count(),
        9,
        "every take drawn: {map}"
    );
}

/// `--control-allow` and `--frames-allow` lie over their keys, checked as the keys are: a
/// network that is not one is a usage error naming the key.
#[test]
fn serve_takes_the_allow_lists_as_flags() {
    for (flag, key) in [
        ("--control-allow", "control_allow"),
        ("--frames-allow", "frames_allow"),
    ] {
        let out = crate::common::run(&[
            "serve",
            "--model",
            "no-such-model.json",
            flag,
            "10.0.0.0/8,192.168.1.0/33",
        ]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{flag}: {err}");
        assert!(
            err.contains(key) && err.contains("192.168.1.0/33"),
            "{flag}: {err}"
        );
    }
}

/// `convert --start/--end` keeps a frame or time range (the rest before and after a
/// sentence), its frames keeping their numbers.
#[test]
fn convert_keeps_a_frame_or_time_range() {
    let dir = tempfile::tempdir().expect("temp dir");
    let input = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../replay/tests/fixtures/NoseMoCap_first60.trc");
    let whole = replay::load(&input).expect("the fixture loads");
    let first = whole.first_frame;
    let by_frame = dir.path().join("frames.csv");
    let (start, end) = ((first + 10).to_string(), (first + 29).to_string());
    ok(&[
        "convert",
        p(&input),
        p(&by_frame),
        "--start",
        &start,
        "--end",
        &end,
    ]);
    let cut = replay::load(&by_frame).expect("written");
    assert_eq!((cut.n_frames(), cut.first_frame), (20, first + 10));
    assert_eq!(cut.frame(0), whole.frame(10));
    let by_time = dir.path().join("time.csv");
    let secs = format!("{}s", 10.0 / whole.rate_hz);
    ok(&["convert", p(&input), p(&by_time), "--start", &secs]);
    let cut = replay::load(&by_time).expect("written");
    assert_eq!(cut.n_frames(), whole.n_frames() - 10);
    let out = crate::common::run(&[
        "convert",
        p(&input),
        p(&by_time),
        "--start",
        "1000000",
        "--force",
    ]);
    assert_eq!(out.status.code(), Some(1), "an empty range is refused");
}

/// `analyze` without a regions file points to `emoshift regions`, whose proposal lets the
/// analysis run (Motive's `Face:` prefix: the module's unit test).
#[test]
fn regions_proposes_a_file_that_analyze_takes() {
    let dir = tempfile::tempdir().expect("temp dir");
    let session = dir.path().join("s");
    ok(&[
        "synth",
        "--out",
        p(&session),
        "--seed",
        "4",
        "--sentences",
        "2",
    ]);
    std::fs::remove_file(session.join("regions.toml")).expect("synth wrote one");
    let manifest = session.join("session.toml");
    let model = dir.path().join("model.json");
    ok(&["train", "--manifest", p(&manifest), "--out", p(&model)]);
    let analyze = |extra: &[&str]| {
        let report = dir.path().join("report");
        let mut args = vec![
            "analyze",
            "--model",
            p(&model),
            "--manifest",
            p(&manifest),
            "--out",
            p(&report),
            "--force",
        ];
        args.extend_from_slice(extra);
        crate::common::run(&args)
    };
    let out = analyze(&[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("emoshift regions TAKE --out"), "{err}");
    let regions = dir.path().join("regions.toml");
    let said = ok(&[
        "regions",
        p(&session.join("s01_neutral.c3d")),
        "--out",
        p(&regions),
    ]);
    assert!(
        said.contains("mouth: ") && said.contains("wrote "),
        "{said}"
    );
    let text = std::fs::read_to_string(&regions).expect("written");
    assert!(
        text.lines()
            .filter(|l| l.trim_start().starts_with('"'))
            .all(|l| l.contains("  # ")),
        "a comment on every marker line:\n{text}"
    );
    let out = analyze(&["--regions", p(&regions)]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    // A name the model lacks: the error says it is the model's, and what to do.
    let typo = dir.path().join("typo.toml");
    std::fs::write(&typo, text.replacen("mouth = [", "mouth = [\"Nope\", ", 1)).expect("write");
    let out = analyze(&["--regions", p(&typo)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("names marker \"Nope\", which the model does not have")
            && err.contains("remove or correct the name"),
        "{err}"
    );
    assert!(
        !err.contains("emoshift regions TAKE"),
        "the file exists: {err}"
    );
}
