//! Issue 37: a manifest take's `start`/`end`. A session whose takes are padded with junk
//! frames outside their ranges trains (in memory and streamed) and analyses exactly as the
//! session of the ranges alone; a range that does not fit its take is refused, saying what to
//! write.

use std::path::{Path, PathBuf};

use crate::common::{ok, p, run};
use daemon::offline::analysis::{self, Inputs};
use daemon::offline::progress::Silent;
use daemon::offline::{self};
use replay::session::{FrameOrTime, Session};
use replay::synth::{generate_session, SynthParams};
use replay::Take;

/// The sessions of one synthetic recording, written under a folder each.
struct Sessions {
    /// The takes as recorded.
    plain: PathBuf,
    /// Each take padded with junk before and after, its range in the manifest.
    trimmed: PathBuf,
    /// The padded takes, used whole.
    padded: PathBuf,
}

/// `take` with `before` and `after` junk frames around it (the take backwards, its face 1.4
/// times as large, one marker missing), numbered so that its own frames keep their numbers.
fn padded(take: &Take, before: usize, after: usize) -> Take {
    let mut out = Take::new(take.labels.clone(), take.rate_hz, take.first_frame);
    let junk = |out: &mut Take, k: usize| {
        let f = take.n_frames() - 1 - k % take.n_frames();
        let xyz: Vec<f32> = take.frame(f).iter().map(|v| v * 1.4).collect();
        let mut missing = take.frame_missing(f).to_vec();
        let gone = k % missing.len();
        missing[gone] = true;
        out.push_frame(&xyz, &missing);
    };
    (0..before).for_each(|k| junk(&mut out, k));
    for f in 0..take.n_frames() {
        out.push_frame(take.frame(f), take.frame_missing(f));
    }
    (0..after).for_each(|k| junk(&mut out, before + k));
    out
}

/// Writes the three sessions (C3D takes, one TRC and one CSV) with the synthetic regions.
fn sessions(dir: &Path) -> Sessions {
    let params = SynthParams {
        seed: 37,
        sentences: 3,
        emotions: ["neutral", "happy", "sad"].map(String::from).to_vec(),
        emotion_dims: 1,
        ..SynthParams::default()
    };
    let s = generate_session(&params, replay::Format::C3d).expect("session");
    let out = Sessions {
        plain: dir.join("plain"),
        trimmed: dir.join("trimmed"),
        padded: dir.join("padded"),
    };
    let mut manifests = [s.session.clone(), s.session.clone(), s.session.clone()];
    for (i, take) in s.takes.iter().enumerate() {
        let ext = ["trc", "csv"].get(i).copied().unwrap_or("c3d");
        let (before, after) = (30 + 7 * i, 45);
        let mut plain = take.clone();
        plain.first_frame = 1 + before as i64;
        let mut long = padded(&plain, before, after);
        long.first_frame = 1;
        let file = format!("take{i}.{ext}");
        for (m, (folder, t)) in manifests.iter_mut().zip([
            (&out.plain, &plain),
            (&out.trimmed, &long),
            (&out.padded, &long),
        ]) {
            std::fs::create_dir_all(folder).expect("folder");
            replay::save(&folder.join(&file), t).expect("write take");
            m.takes[i].file = file.clone();
        }
        // The start as a frame number, the end as a frame or as a time.
        let entry = &mut manifests[1].takes[i];
        entry.start = Some(FrameOrTime::Frame(plain.first_frame));
        let last = before + take.n_frames() - 1;
        entry.end = Some(match i % 2 {
            0 => FrameOrTime::Frame(1 + last as i64),
            _ => FrameOrTime::Seconds(last as f64 / take.rate_hz),
        });
    }
    for (m, folder) in manifests
        .iter()
        .zip([&out.plain, &out.trimmed, &out.padded])
    {
        std::fs::write(folder.join("session.toml"), m.to_toml().expect("toml")).expect("write");
        let regions = s.regions.to_toml().expect("toml");
        std::fs::write(folder.join("regions.toml"), regions).expect("regions");
    }
    out
}

/// Trains on the session in `folder` through the CLI; returns the model.
fn train(folder: &Path, extra: &[&str]) -> ica_core::model::IcaModel {
    let (manifest, model) = (folder.join("session.toml"), folder.join("model.json"));
    let mut args = vec!["train", "--manifest", p(&manifest), "--out", p(&model)];
    args.extend(["--components", "6", "--force"]);
    args.extend(extra);
    ok(&args);
    offline::load_model(&model).expect("model")
}

fn same_model(a: &ica_core::model::IcaModel, b: &ica_core::model::IcaModel) -> bool {
    a.mixing() == b.mixing() && a.mean() == b.mean()
}

#[test]
fn issue_37_a_trimmed_take_trains_and_analyses_on_its_range_only() {
    let dir = tempfile::tempdir().expect("temp dir");
    let s = sessions(dir.path());
    for extra in [&[][..], &["--stream"][..]] {
        let want = train(&s.plain, extra);
        let got = train(&s.trimmed, extra);
        assert!(same_model(&got, &want), "{extra:?}: trimmed != plain");
        let junk = train(&s.padded, extra);
        assert!(
            !same_model(&junk, &want),
            "{extra:?}: the junk frames change nothing"
        );
    }

    // analyze, streamed take by take, on the plain session's model.
    let model_path = s.plain.join("model.json");
    let model = offline::load_model(&model_path).expect("model");
    let report = |folder: &Path| {
        let manifest = folder.join("session.toml");
        let session = offline::load_session(&manifest).expect("session");
        let regions_path = folder.join("regions.toml");
        let regions = analysis::resolve_regions(&regions_path, &model).expect("regions");
        let inputs = Inputs {
            model: &model,
            model_path: &model_path,
            manifest_path: &s.plain.join("session.toml"),
            regions_path: &s.plain.join("regions.toml"),
        };
        let streamed = analysis::analyze_session(&inputs, &session, &regions, &mut Silent);
        let (streamed, _) = streamed.expect("analysed");
        let held = analysis::project_session(&model, &session).expect("projected");
        let held = analysis::analyze(&inputs, &held, &regions).expect("analysed");
        let json = |r: &analysis::Report| serde_json::to_value(r).expect("json");
        (json(&streamed), json(&held))
    };
    let (plain, trimmed) = (report(&s.plain), report(&s.trimmed));
    assert_eq!(trimmed.0, plain.0, "streamed analysis");
    assert_eq!(trimmed.1, plain.1, "analysis of the held takes");
}

#[test]
fn issue_37_a_range_that_does_not_fit_its_take_is_refused_saying_what_to_write() {
    let dir = tempfile::tempdir().expect("temp dir");
    let s = sessions(dir.path());
    let manifest = s.trimmed.join("session.toml");
    let session = Session::load(&manifest).expect("session");
    let refused = |edit: &dyn Fn(&mut Session), needle: &str| {
        let mut bad = session.clone();
        edit(&mut bad);
        std::fs::write(&manifest, bad.to_toml().expect("toml")).expect("write");
        let out = dir.path().join("model.json");
        let run = run(&["train", "--manifest", p(&manifest), "--out", p(&out)]);
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success() && err.contains(needle), "{err}");
        assert!(!out.exists(), "no model from a refused session");
    };
    refused(
        &|s| s.takes[2].end = Some(FrameOrTime::Frame(100_000)),
        "take2.c3d: start/end in the session manifest: end = 100000 is outside the take, \
         which has frames 1 to",
    );
    refused(
        &|s| s.takes[0].start = Some(FrameOrTime::Seconds(1e4)),
        "start = 10000s is outside the take",
    );
    refused(
        &|s| s.takes[1].end = Some(FrameOrTime::Frame(2)),
        "end = 2 is before start = 38",
    );
}
