//! Issue 34 from the command line: `synth` variant flags, `inject` on a real capture, and the
//! analysis that tells whether the emotion components would be sound axes.

use std::path::Path;

use crate::common::{ok, p, run};

/// `train` then `analyze --write-model` of the session at `manifest` into `model`, the report
/// in `report`; returns analyze's output.
fn train_and_analyze(manifest: &Path, model: &Path, report: &Path) -> String {
    ok(&["train", "--manifest", p(manifest), "--out", p(model)]);
    analyze(manifest, model, report)
}

fn analyze(manifest: &Path, model: &Path, report: &Path) -> String {
    ok(&[
        "analyze",
        "--model",
        p(model),
        "--manifest",
        p(manifest),
        "--out",
        p(report),
        "--write-model",
    ])
}

/// Runs a command that must be refused as a usage error (exit code 2) naming `needle`.
fn usage(args: &[&str], needle: &str) {
    let out = run(args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "emoshift {args:?}: {err}");
    assert!(err.contains(needle), "{err:?} should name {needle:?}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn synth_variant_flags_write_their_session_and_refuse_bad_values() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("s");
    let text = ok(&[
        "synth",
        "--out",
        p(&out),
        "--sentences",
        "5",
        "--emotion-dims",
        "2",
        "--emotions",
        "neutral,happy,sad,angry",
        "--takes",
        "angry=3",
        "--speech-rate",
        "sad=0.85",
        "--take-intensity",
        "0.3",
        "--interaction",
        "0.05",
        "--spread-effects",
        "1",
    ]);
    assert!(text.contains("wrote 18 takes"), "{text}");
    assert!(text.contains("variants: take intensity ±0.3"), "{text}");
    let manifest = std::fs::read_to_string(out.join("session.toml")).expect("manifest");
    assert_eq!(manifest.matches("emotion = \"angry\"").count(), 3);
    let truth = std::fs::read_to_string(out.join("truth/mixing.json")).expect("truth");
    assert!(
        truth.contains("angry in 3 sentences"),
        "the truth records the variants"
    );
    let bad = dir.path().join("bad");
    for (flag, value, needle) in [
        ("--takes", "angry=9", "takes 9"),
        ("--takes", "calm=2", "takes names emotion \"calm\""),
        ("--speech-rate", "angry=5", "speech rate 5"),
        ("--take-intensity", "2", "take intensity 2"),
        ("--takes", "angry", "name=number"),
    ] {
        usage(
            &[
                "synth",
                "--out",
                p(&bad),
                "--sentences",
                "5",
                "--emotions",
                "neutral,angry",
                flag,
                value,
            ],
            needle,
        );
    }
}

#[test]
fn inject_cuts_a_real_capture_into_a_paired_session_that_analyses_as_one() {
    let dir = tempfile::tempdir().expect("temp dir");
    let capture =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../replay/tests/fixtures/Facial-Sing.c3d");
    let regions =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/facial-sing.regions.toml");
    let out = dir.path().join("sing");
    let text = ok(&[
        "inject",
        p(&capture),
        "--out",
        p(&out),
        "--seed",
        "4",
        "--regions",
        p(&regions),
    ]);
    assert!(
        text.contains("wrote 18 takes: 6 sentences x 3 levels (level1, level2, level3)"),
        "{text}"
    );
    assert!(
        text.contains("root-1"),
        "the field is in the head frame: {text}"
    );
    let truth: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("truth/inject.json")).expect("truth"),
    )
    .expect("json");
    assert_eq!(truth["cuts"].as_array().map(Vec::len), Some(18));
    assert_eq!(truth["field_mm"], 3.0);
    let model = out.join("model.json");
    let analysed = train_and_analyze(&out.join("session.toml"), &model, &out.join("report"));
    assert!(analysed.contains("space: 1 axes fitted"), "{analysed}");
    assert!(analysed.contains("conditioning: "), "{analysed}");
    let html = std::fs::read_to_string(out.join("report/report.html")).expect("report");
    assert!(
        html.contains("Axes of the edits"),
        "report.html shows the axes"
    );
    let shown = ok(&["inspect", p(&model)]);
    assert!(shown.contains("1 axes fitted over all"), "{shown}");
    assert!(shown.contains("conditioning:"), "{shown}");
    // A regions file proposed from one of its takes must not name Unlabeled1, which is
    // missing in 99 % of the frames and so not in the model: analyze takes it as written.
    let proposed = dir.path().join("proposed.toml");
    let said = ok(&[
        "regions",
        p(&out.join("s01_level1.c3d")),
        "--out",
        p(&proposed),
    ]);
    assert!(said.contains("left out Unlabeled1: missing in"), "{said}");
    let analysed = ok(&[
        "analyze",
        "--model",
        p(&model),
        "--manifest",
        p(&out.join("session.toml")),
        "--regions",
        p(&proposed),
        "--out",
        p(&dir.path().join("proposed-report")),
    ]);
    assert!(analysed.contains("wrote "), "{analysed}");
    usage(
        &[
            "inject",
            p(&capture),
            "--out",
            p(&dir.path().join("x")),
            "--levels",
            "1",
        ],
        "--levels 1",
    );
    usage(
        &[
            "inject",
            p(&capture),
            "--out",
            p(&dir.path().join("y")),
            "--sentence-s",
            "100",
        ],
        "shorter",
    );
}

#[test]
fn an_ill_conditioned_component_space_is_reported_with_what_was_done() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("s");
    ok(&[
        "synth",
        "--out",
        p(&out),
        "--seed",
        "3",
        "--emotion-dims",
        "2",
        "--emotions",
        "neutral,happy,sad,angry",
    ]);
    let manifest = out.join("session.toml");
    let model = out.join("model.json");
    ok(&["train", "--manifest", p(&manifest), "--out", p(&model)]);
    let analyse = |report: &str| {
        let text = analyze(&manifest, &model, &out.join(report));
        let line = text
            .lines()
            .find(|l| l.starts_with("conditioning: "))
            .expect("a conditioning line")
            .to_string();
        let m = ica_core::IcaModel::load(std::fs::File::open(&model).expect("model"))
            .expect("valid model");
        let c = m
            .emotion()
            .conditioning
            .clone()
            .expect("recorded in the model");
        (line, c)
    };
    // As trained, one component per emotion direction: sound axes.
    let (line, c) = analyse("plain");
    assert!(!c.ill_conditioned, "{line}");
    assert_eq!((c.components.len(), c.dims), (2, 2), "{line}");
    assert!(line.contains("are sound axes"), "{line}");
    // The same model split another way: every component carries some of both directions.
    crate::transfer::turn_model(&model, 11);
    let (line, c) = analyse("turned");
    assert!(c.ill_conditioned, "{line}");
    assert!(c.components.len() > c.dims, "{line}");
    assert!(line.contains("ill-conditioned as axes"), "{line}");
    assert!(
        line.contains("2 axes fitted over all 8 components"),
        "{line}"
    );
    let html = std::fs::read_to_string(out.join("turned/report.html")).expect("report");
    assert!(
        html.contains("<b>Ill-conditioned:</b>"),
        "report.html says so"
    );
}
