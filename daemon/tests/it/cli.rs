//! The command line as a user runs it: formats, errors, the offline round trip, and analysis
//! without emotion pairs.

use std::path::Path;

use crate::common::{ok, p, run};

/// Runs a command that must fail: exit code 1, one line on stderr naming `needle`, no panic.
fn fails(args: &[&str], needle: &str) {
    let out = run(args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "emoshift {args:?}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    assert!(err.contains(needle), "{err:?} should name {needle:?}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn synth_output_reads_back_identically_in_all_three_formats() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut takes = Vec::new();
    for format in ["c3d", "trc", "csv"] {
        let out = dir.path().join(format);
        ok(&[
            "synth",
            "--out",
            p(&out),
            "--sentences",
            "1",
            "--seed",
            "4",
            "--format",
            format,
        ]);
        takes.push(replay::load(&out.join(format!("s01_happy.{format}"))).expect("take loads"));
    }
    let (a, b, c) = (&takes[0], &takes[1], &takes[2]);
    for other in [b, c] {
        assert_eq!(a.labels, other.labels);
        assert_eq!(a.rate_hz, other.rate_hz);
        assert_eq!(a.first_frame, other.first_frame);
        assert_eq!(a.missing, other.missing);
        let worst = a
            .positions
            .iter()
            .zip(&other.positions)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0f32, f32::max);
        assert!(worst < 1e-3, "formats differ by {worst} mm");
    }
}

#[test]
fn synth_writes_an_emotion_space_with_explicit_points() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("space");
    let printed = ok(&[
        "synth",
        "--out",
        p(&out),
        "--sentences",
        "1",
        "--emotions",
        "neutral,sad,angry,calm",
        "--point",
        "calm=0.3,-0.4",
    ]);
    assert!(printed.contains("sad (-0.6, -0.8)"), "{printed}");
    let truth = replay::synth::load_truth(&out).expect("truth loads");
    let m = &truth.mixing;
    assert_eq!(
        m.emotion_columns(),
        vec![4, 5],
        "two directions from the point"
    );
    assert_eq!(m.point_of("calm"), Some(vec![0.3, -0.4]));
    assert_eq!(m.point_of("angry"), Some(vec![-0.2, 1.0]));
    assert_eq!(truth.takes.len(), 4);
    let base = ["synth", "--out", p(&out), "--sentences", "1"];
    for (extra, needle) in [
        (&["--emotion-dims", "4"][..], "got 4"),
        (
            &["--emotion-dims", "3", "--point", "happy=1,0"][..],
            "has 2 coordinates",
        ),
        (&["--point", "joy=1"][..], "\"joy\""),
        (&["--point", "happy=1,x"][..], "happy=1,x"),
    ] {
        let args: Vec<&str> = base.iter().chain(extra).copied().collect();
        let out = run(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(needle), "{err:?} should name {needle:?}");
    }
}

#[test]
fn bad_input_gets_one_clear_line_and_exit_code_1() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    fails(&["info", p(&d.join("nope.c3d"))], "nope.c3d");
    std::fs::write(d.join("x.xyz"), "hello").expect("write");
    fails(&["info", p(&d.join("x.xyz"))], "unknown take format");
    std::fs::write(
        d.join("nan.csv"),
        "frame,time,a_x,a_y,a_z\n1,0,1,2,inf\n2,0.01,1,2,3\n",
    )
    .expect("write");
    fails(&["info", p(&d.join("nan.csv"))], "nan.csv");
    std::fs::write(
        d.join("empty.csv"),
        "# rate_hz=120 units=mm\nframe,time,a_x,a_y,a_z\n",
    )
    .expect("write");
    fails(
        &[
            "train",
            p(&d.join("empty.csv")),
            "--out",
            p(&d.join("m.json")),
        ],
        "no frames",
    );
    // Two markers moving together: rank 1, so 5 components cannot exist.
    let mut rows = String::from("# rate_hz=100 units=mm\nframe,time,a_x,a_y,a_z,b_x,b_y,b_z\n");
    for f in 0..200 {
        let v = (f as f64 * 0.1).sin();
        rows += &format!("{},{},{v},0,0,{v},0,0\n", f + 1, f as f64 / 100.0);
    }
    std::fs::write(d.join("rank.csv"), rows).expect("write");
    fails(
        &[
            "train",
            p(&d.join("rank.csv")),
            "--out",
            p(&d.join("m.json")),
            "--components",
            "5",
            "--head-reference",
            "none",
        ],
        "rank",
    );
    std::fs::write(
        d.join("bad.json"),
        "{\"format_version\": 1, \"labels\": []}",
    )
    .expect("write");
    fails(&["inspect", p(&d.join("bad.json"))], "bad.json");
    let out = run(&[
        "edit",
        "--model",
        "m.json",
        "x.c3d",
        "--out",
        "y.c3d",
        "--translate",
        "zero=1",
    ]);
    assert_eq!(
        out.status.code(),
        Some(2),
        "a malformed flag is a usage error"
    );
}

#[test]
fn train_project_edit_round_trip_on_synth_output() {
    let dir = tempfile::tempdir().expect("temp dir");
    let s = dir.path().join("s");
    ok(&["synth", "--out", p(&s), "--sentences", "2", "--seed", "9"]);
    let model = dir.path().join("m.json");
    let out = ok(&[
        "train",
        "--manifest",
        p(&s.join("session.toml")),
        "--out",
        p(&model),
        "--components",
        "8",
    ]);
    assert!(out.contains("converged"), "{out}");
    let csv = dir.path().join("u.csv");
    ok(&[
        "project",
        "--model",
        p(&model),
        p(&s.join("s01_happy.c3d")),
        "--out",
        p(&csv),
    ]);
    let text = std::fs::read_to_string(&csv).expect("components");
    let header = text.lines().next().expect("header");
    assert_eq!(header, "frame,time,c0,c1,c2,c3,c4,c5,c6,c7");
    let take = replay::load(&s.join("s01_happy.c3d")).expect("take");
    assert_eq!(text.lines().count(), take.n_frames() + 1);
    let edited = dir.path().join("e.trc");
    ok(&[
        "edit",
        "--model",
        p(&model),
        p(&s.join("s01_happy.c3d")),
        "--out",
        p(&edited),
        "--translate",
        "0=2",
        "--gain",
        "1=0.5",
    ]);
    let e = replay::load(&edited).expect("edited take");
    assert_eq!(e.n_frames(), take.n_frames());
    assert_eq!(e.labels, take.labels);
    // A translate of two units moves markers by about twice component 0's mixing norm.
    let moved = e
        .positions
        .iter()
        .zip(&take.positions)
        .map(|(a, b)| f64::from(a - b).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(moved > 1.0, "the edit changed nothing ({moved})");
    // Negative values are values, and the live controls' bounds hold offline.
    let happy = s.join("s01_happy.c3d");
    let take = p(&happy);
    let back = dir.path().join("back.trc");
    ok(&[
        "edit",
        "--model",
        p(&model),
        take,
        "--out",
        p(&back),
        "--translate",
        "0=-2",
    ]);
    let usage = |args: &[&str], needle: &str| {
        let out = run(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "emoshift {args:?}: {err}");
        assert!(err.contains(needle), "{err:?} should name {needle:?}");
    };
    let other = dir.path().join("other.trc");
    let other = p(&other);
    for (flag, value, needle) in [
        ("--gain", "1=11", "outside -10..10"),
        ("--translate", "1=1e6", "outside -100..100"),
    ] {
        usage(
            &[
                "edit",
                "--model",
                p(&model),
                take,
                "--out",
                other,
                flag,
                value,
            ],
            needle,
        );
    }
    // An output named as a take format the command does not write.
    let wrong = dir.path().join("u.c3d");
    let wrong = p(&wrong);
    usage(
        &["project", "--model", p(&model), take, "--out", wrong],
        "name the output .csv",
    );
    usage(
        &["train", take, "--out", p(&dir.path().join("m.trc"))],
        "name the output .json",
    );
    assert!(!dir.path().join("u.c3d").exists() && !dir.path().join("m.trc").exists());
}

#[test]
fn analyze_without_pairs_reports_regions_and_why_emotion_is_missing() {
    let dir = tempfile::tempdir().expect("temp dir");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let take = root.join("../replay/tests/fixtures/Facial-Sing.c3d");
    let regions = root.join("tests/fixtures/facial-sing.regions.toml");
    let model = dir.path().join("m.json");
    ok(&[
        "train",
        p(&take),
        "--out",
        p(&model),
        "--regions",
        p(&regions),
    ]);
    let manifest = dir.path().join("session.toml");
    std::fs::write(
        &manifest,
        format!(
            "rate_hz = 100\n[[take]]\nfile = {:?}\nsentence = \"song\"\nemotion = \"neutral\"\n",
            p(&take)
        ),
    )
    .expect("manifest");
    let report_dir = dir.path().join("report");
    let out = ok(&[
        "analyze",
        "--model",
        p(&model),
        "--manifest",
        p(&manifest),
        "--regions",
        p(&regions),
        "--out",
        p(&report_dir),
    ]);
    assert!(out.contains("emotion not measured"), "{out}");
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(report_dir.join("report.json")).expect("report"),
    )
    .expect("json");
    assert_eq!(report["emotion_measured"], false);
    let roles: Vec<&str> = report["components"]
        .as_array()
        .expect("components")
        .iter()
        .map(|c| c["role"].as_str().expect("role"))
        .collect();
    assert!(
        roles.contains(&"speech"),
        "a singer's mouth moves: {roles:?}"
    );
    assert!(!roles.contains(&"emotion"));
}

#[test]
fn a_head_reference_asked_for_and_not_used_is_a_warning_and_a_regions_file_is_not() {
    // synth without --head-motion: the head is still, so stabilising on it would add more
    // pose error than it removes, whoever named it.
    let dir = tempfile::tempdir().expect("temp dir");
    let s = dir.path().join("s");
    ok(&["synth", "--out", p(&s), "--sentences", "2", "--seed", "4"]);
    let manifest = s.join("session.toml");
    let model = dir.path().join("m.json");
    let train = |extra: &[&str]| {
        let mut args = vec![
            "train",
            "--force",
            "--manifest",
            p(&manifest),
            "--out",
            p(&model),
        ];
        args.extend(extra);
        let out = ok(&args);
        let json = std::fs::read_to_string(&model).expect("model");
        (out, json)
    };
    // The session's regions file names the head markers: a description, not a request.
    let (out, json) = train(&[]);
    assert!(
        out.contains("head reference (named): not stabilised"),
        "{out}"
    );
    assert!(!out.contains("--head-reference"), "{out}");
    assert!(!json.contains("\"requested\""), "not written when false");
    let (out, json) = train(&["--head-reference", "Head*"]);
    let warning = out
        .lines()
        .find(|l| l.contains("named by --head-reference"))
        .unwrap_or_else(|| panic!("a warning: {out}"));
    assert!(
        warning.contains("HeadFront") && warning.contains("not stabilised"),
        "{warning}"
    );
    assert!(
        json.contains("named by --head-reference"),
        "in the model's warnings"
    );
}

/// What `train` says it filled is what `info` says is missing, plus the glitches it dropped,
/// counted the same way: marker samples (Facial-Sing, a capture emoshift did not make).
#[test]
fn train_counts_gaps_in_the_marker_samples_info_counts() {
    let dir = tempfile::tempdir().expect("temp dir");
    let take =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../replay/tests/fixtures/Facial-Sing.c3d");
    let info: serde_json::Value =
        serde_json::from_str(&ok(&["info", p(&take), "--json"])).expect("info json");
    let out = ok(&["train", p(&take), "--out", p(&dir.path().join("m.json"))]);
    let number_after = |prefix: &str| -> usize {
        let line = out
            .lines()
            .find(|l| l.starts_with(prefix))
            .unwrap_or_else(|| panic!("no {prefix:?} in {out}"));
        line[prefix.len()..]
            .split_whitespace()
            .next()
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("no count in {line:?}"))
    };
    let excluded: Vec<&str> = out
        .lines()
        .filter_map(|l| l.strip_prefix("excluded marker "))
        .filter_map(|l| l.split(':').next())
        .collect();
    assert_eq!(excluded, ["Unlabeled1"], "{out}");
    let missing: u64 = info["marker_list"]
        .as_array()
        .expect("markers")
        .iter()
        .filter(|m| !excluded.contains(&m["label"].as_str().expect("label")))
        .map(|m| m["missing"].as_u64().expect("count"))
        .sum();
    let glitches = number_after("glitches: ");
    let gaps = number_after("gaps: ");
    assert!(glitches > 0 && missing > 0, "{out}");
    assert_eq!(gaps as u64, missing + glitches as u64, "{out}");
}

/// A named head reference that cannot be used says who named it and why: a marker the take
/// lacks, or one training left out for being missing (Facial-Sing's `Unlabeled1`), and not
/// a regions file, which none was given.
#[test]
fn a_head_reference_that_cannot_be_used_names_the_flag_and_the_reason() {
    let dir = tempfile::tempdir().expect("temp dir");
    let take =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../replay/tests/fixtures/Facial-Sing.c3d");
    let out = dir.path().join("m.json");
    for (head, needle) in [
        ("Nope", "--head-reference names marker \"Nope\", which the take does not have"),
        (
            "Unlabeled1,root-1,root-2",
            "--head-reference names marker \"Unlabeled1\", which training left out: it is missing in 98.8 % of the frames",
        ),
        ("zz*", "--head-reference matches no marker"),
    ] {
        let args = ["train", p(&take), "--head-reference", head, "--out", p(&out)];
        fails(&args, needle);
        let err = String::from_utf8_lossy(&run(&args).stderr).into_owned();
        assert!(!err.contains("region"), "{err}");
    }
}

/// A corrupt parameter byte that makes c3dio panic (one zeroed byte of a label in a c3d.org
/// sample): the reader catches the panic and decodes the file itself, and the user sees the
/// take, not a panic message and a backtrace.
#[test]
fn a_c3dio_panic_on_a_corrupt_file_stays_quiet_and_the_take_reads() {
    let dir = tempfile::tempdir().expect("temp dir");
    let sample = Path::new(env!("CARGO_MANIFEST_DIR")).join("../replay/tests/fixtures/Eb015pi.c3d");
    let mut bytes = std::fs::read(sample).expect("fixture");
    bytes[3352] = 0;
    let (take, info) = replay::c3d::read_with_info(&bytes).expect("our decoder reads it");
    assert_eq!(
        info.c3dio_error.as_deref(),
        Some("c3dio panicked"),
        "the corruption no longer makes c3dio panic: pick another byte"
    );
    assert!(!replay::c3d::catching_c3dio_panic());
    let corrupt = dir.path().join("corrupt.c3d");
    std::fs::write(&corrupt, &bytes).expect("write");
    let out = run(&["info", p(&corrupt)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains(&format!("frames:   {} ", take.n_frames())),
        "{text}"
    );
}

/// Analog data (16 channels in a c3d.org sample) is not read: `info` says it is there, and
/// `convert` says the output leaves it out; a take without any says nothing.
#[test]
fn analog_channels_left_out_are_said_so() {
    let dir = tempfile::tempdir().expect("temp dir");
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("../replay/tests/fixtures");
    let with = fixtures.join("Eb015pi.c3d");
    assert!(ok(&["info", p(&with)]).contains("analog:   64 samples per frame (not read"));
    let out = ok(&["convert", p(&with), p(&dir.path().join("a.trc"))]);
    assert!(
        out.contains("has analog data (64 samples per frame), which emoshift does not read"),
        "{out}"
    );
    let without = fixtures.join("Facial-Sing.c3d");
    assert!(!ok(&["info", p(&without)]).contains("analog"));
    let out = ok(&["convert", p(&without), p(&dir.path().join("f.trc"))]);
    assert!(!out.contains("warning"), "{out}");
}
