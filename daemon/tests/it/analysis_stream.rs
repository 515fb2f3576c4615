//! Issue 18: `analyze` streamed sentence by sentence gives the report of the whole session held
//! in memory (every take loaded and projected at once, every pair aligned together), on a
//! synthetic session of several sentences in four emotions whose manifest interleaves the
//! sentences (so the streamed sums run in another order), with a TRC and a CSV take among the
//! C3D ones (headers that declare their length, and one that does not). One take is warped
//! in time far from the diagonal and another is three times the others' length: the DTW band,
//! a share of the session's longest take, binds on the warped take's pairs only if a
//! sentence's band came from that sentence alone.

use std::path::Path;

use crate::common::{ok, p};
use daemon::offline::analysis::{self, Inputs};
use daemon::offline::progress::Silent;
use daemon::offline::{self};
use replay::synth::{generate_session, SynthParams};
use replay::Take;
use serde_json::Value;

/// Relative tolerance on every number of the report. `d_region,i` is a difference of two
/// square roots of nearly equal sums for a component that barely moves the region, so its
/// error is relative to the region's scale, not to itself: it is compared against the largest
/// `|d_region|` of the region.
const REL: f64 = 1e-12;

/// Writes a session of `sentences` sentences in four emotions, ordered emotion by emotion,
/// and trains a model on it; returns the manifest and model paths.
fn session(dir: &Path, sentences: usize) -> (std::path::PathBuf, std::path::PathBuf) {
    let params = SynthParams {
        seed: 18,
        sentences,
        emotions: ["neutral", "happy", "frustrated", "sad"]
            .map(String::from)
            .to_vec(),
        emotion_dims: 2,
        ..SynthParams::default()
    };
    let mut s = generate_session(&params, replay::Format::C3d).expect("session");
    s.takes[1] = warped(&s.takes[1]);
    let last = s.takes.len() - 1;
    s.takes[last] = [&s.takes[last]; 3].map(|t| t.clone()).into_iter().fold(
        Take::new(s.takes[last].labels.clone(), s.takes[last].rate_hz, 1),
        |mut long, t| {
            for f in 0..t.n_frames() {
                long.push_frame(t.frame(f), t.frame_missing(f));
            }
            long
        },
    );
    for (i, (take, entry)) in s.takes.iter().zip(&mut s.session.takes).enumerate() {
        // One TRC and one CSV take: declared and undeclared lengths.
        let ext = match i {
            1 => "trc",
            2 => "csv",
            _ => "c3d",
        };
        entry.file = format!("take{i}.{ext}");
        replay::save(&dir.join(&entry.file), take).expect("write take");
    }
    s.session.takes.sort_by(|a, b| a.emotion.cmp(&b.emotion));
    let manifest = dir.join("session.toml");
    std::fs::write(&manifest, s.session.to_toml().expect("toml")).expect("manifest");
    let regions = s.regions.to_toml().expect("toml");
    std::fs::write(dir.join("regions.toml"), regions).expect("regions");
    let model = dir.join("model.json");
    let (m, mf) = (p(&model), p(&manifest));
    ok(&["train", "--manifest", mf, "--out", m, "--components", "10"]);
    (manifest, model)
}

/// `take` at twice its speed for its first half, then at half its speed: far from the
/// diagonal of an alignment with the same sentence at an even pace.
fn warped(take: &Take) -> Take {
    let n = take.n_frames();
    let mut out = Take::new(take.labels.clone(), take.rate_hz, take.first_frame);
    let frames = (0..n / 2).step_by(2).chain((n / 2..n).flat_map(|f| [f, f]));
    for f in frames {
        out.push_frame(take.frame(f), take.frame_missing(f));
    }
    out
}

/// Every number of `a` within [`REL`] of `b`'s, everything else equal.
fn assert_close(a: &Value, b: &Value, at: &str) {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().expect("f64"), y.as_f64().expect("f64"));
            let scale = x.abs().max(y.abs());
            assert!((x - y).abs() <= REL * scale, "{at}: {x} vs {y}");
        }
        (Value::Array(x), Value::Array(y)) => {
            assert_eq!(x.len(), y.len(), "{at}: lengths");
            for (i, (u, v)) in x.iter().zip(y).enumerate() {
                assert_close(u, v, &format!("{at}[{i}]"));
            }
        }
        (Value::Object(x), Value::Object(y)) => {
            let keys = |o: &serde_json::Map<String, Value>| o.keys().cloned().collect::<Vec<_>>();
            assert_eq!(keys(x), keys(y), "{at}: keys");
            for (k, u) in x {
                assert_close(u, &y[k], &format!("{at}.{k}"));
            }
        }
        _ => assert_eq!(a, b, "{at}"),
    }
}

fn json(report: &analysis::Report) -> Value {
    serde_json::to_value(report).expect("json")
}

/// Compares every component's `d_region` within [`REL`] of the region's largest, then removes
/// them so [`assert_close`] checks the rest.
fn assert_regions_close(a: &mut Value, b: &mut Value) {
    let take = |v: &mut Value| -> Vec<Value> {
        let components = v["components"].as_array_mut().expect("components");
        components
            .iter_mut()
            .map(|c| c["d_region"].take())
            .collect()
    };
    let (ra, rb) = (take(a), take(b));
    for name in ra[0].as_object().expect("regions").keys() {
        let of = |r: &[Value]| -> Vec<f64> {
            r.iter().map(|c| c[name].as_f64().expect("f64")).collect()
        };
        let (x, y) = (of(&ra), of(&rb));
        let scale = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(scale > 0.0, "{name}: all zero");
        for (k, (u, v)) in x.iter().zip(&y).enumerate() {
            assert!((u - v).abs() <= REL * scale, "c{k} d_{name}: {u} vs {v}");
        }
    }
}

#[test]
fn issue_18_streamed_analysis_matches_the_whole_session() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (manifest, model_path) = session(dir.path(), 5);
    let model = offline::load_model(&model_path).expect("model");
    let session = offline::load_session(&manifest).expect("session");
    let regions_path = dir.path().join("regions.toml");
    let regions = analysis::resolve_regions(&regions_path, &model).expect("regions");
    let inputs = Inputs {
        model: &model,
        model_path: &model_path,
        manifest_path: &manifest,
        regions_path: &regions_path,
    };

    let takes = analysis::project_session(&model, &session).expect("projected");
    let whole = analysis::analyze(&inputs, &takes, &regions).expect("whole");
    let whole_timeline = analysis::timeline_of(&whole, &takes);
    drop(takes);
    let (streamed, timeline) =
        analysis::analyze_session(&inputs, &session, &regions, &mut Silent).expect("streamed");

    assert!(
        whole.emotion_measured && whole.pairs.len() == 5 * 6,
        "{:?}",
        whole.pairs
    );
    assert!(!whole.emotion_components.is_empty(), "an emotion space");
    let (mut a, mut b) = (json(&streamed), json(&whole));
    assert_regions_close(&mut a, &mut b);
    assert_close(&a, &b, "report");
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    analysis::write_report(&a, &whole, &whole_timeline).expect("written");
    analysis::write_report(&b, &streamed, &timeline).expect("written");
    let svg = |d: &Path| std::fs::read_to_string(d.join("timeline.svg")).expect("svg");
    assert!(!timeline.is_empty());
    assert_eq!(svg(&a), svg(&b), "the timeline draws the same takes");
}

#[test]
fn issue_18_analyze_shows_progress_in_a_pipe() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (manifest, model) = session(dir.path(), 2);
    let report = dir.path().join("report");
    let args = ["analyze", "--model", p(&model), "--manifest", p(&manifest)];
    crate::common::shows_progress(
        &[&args[..], &["--out", p(&report)]].concat(),
        &[
            "analyze: reading headers done: 8 takes in ",
            "analyze: analysing done: 8 takes in ",
            "analyze: timeline done: ",
        ],
    );
}

#[test]
fn a_take_whose_header_lies_about_its_length_is_an_error_not_an_abort() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (manifest, model) = session(dir.path(), 2);
    let trc = dir.path().join("take1.trc");
    let text = std::fs::read_to_string(&trc).expect("trc");
    let mut lines: Vec<String> = text.split('\n').map(String::from).collect();
    let mut values: Vec<&str> = lines[2].split('\t').collect();
    values[2] = "99999999999999"; // NumFrames
    lines[2] = values.join("\t");
    std::fs::write(&trc, lines.join("\n")).expect("write trc");
    let report = dir.path().join("report");
    let out = crate::common::run(&[
        "analyze",
        "--model",
        p(&model),
        "--manifest",
        p(&manifest),
        "--out",
        p(&report),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("take1.trc: header declares 99999999999999 frames"),
        "{err}"
    );
}
