//! Issue 37: `edit --start/--end` writes the same range cut from the whole edit (frames
//! before it are edited, not written, so the edit's state reaches it as in the whole take),
//! numbered as the input numbers its frames, streamed whatever the block size, from C3D, TRC
//! and CSV, on a real capture; a range that keeps nothing is refused, saying what to write.

use std::path::Path;

use crate::common::{ok, p, run};
use daemon::offline::edit::{self, edit_take, EditRequest};
use daemon::offline::progress::Silent;
use daemon::offline::trim::{frame_range, FrameOrTime};
use daemon::offline::{self, streamed};
use replay::Take;

const LIMIT: u64 = 1 << 30;

/// `whole` cut to `start..=end`, as `convert --start --end` cuts it.
fn cut(whole: &Take, start: Option<FrameOrTime>, end: Option<FrameOrTime>) -> Take {
    let mut cut = whole.clone();
    cut.keep_frames(frame_range(whole, start, end).expect("a range"));
    cut
}

/// Facial-Sing (NaturalPoint, 38 markers at 100 Hz) under a model trained on it, edited by
/// the live daemon's low-pass edit of a raw translation: CLI, streamed, three formats.
#[test]
fn a_ranged_edit_of_a_real_capture_is_the_whole_edit_cut() {
    let dir = tempfile::tempdir().expect("temp dir");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let capture = root.join("../replay/tests/fixtures/Facial-Sing.c3d");
    let regions = root.join("tests/fixtures/facial-sing.regions.toml");
    let model = dir.path().join("m.json");
    let train = [
        "train",
        p(&capture),
        "--out",
        p(&model),
        "--regions",
        p(&regions),
    ];
    ok(&train);
    let input = offline::load_take(&capture).expect("fixture");
    for ext in ["c3d", "trc", "csv"] {
        let source = dir.path().join(format!("in.{ext}"));
        replay::save(&source, &input).expect("input written");
        let (whole, ranged) = (
            dir.path().join(format!("whole.{ext}")),
            dir.path().join(format!("ranged.{ext}")),
        );
        let edit = [
            "edit",
            "--model",
            p(&model),
            p(&source),
            "--translate",
            "0=1.5",
        ];
        ok(&[&edit[..], &["--gain", "1=0.5", "--out", p(&whole)]].concat());
        // Frame numbers as the file numbers them, and seconds from its first frame.
        let first = input.first_frame + 37;
        let (from, to) = (first.to_string(), "2.5s");
        let range = ["--start", &from, "--end", to, "--block-frames", "16"];
        let text = ok(&[&edit[..], &["--gain", "1=0.5", "--out", p(&ranged)], &range].concat());
        let expected = cut(
            &replay::load(&whole).expect("whole edit"),
            Some(FrameOrTime::Frame(first)),
            Some(FrameOrTime::Seconds(2.5)),
        );
        let got = replay::load(&ranged).expect("ranged edit");
        assert_eq!(got.first_frame, first, "{ext}: numbered as the input");
        assert_eq!(got.n_frames(), 251 - 37, "{ext}");
        assert!(
            text.contains(&format!("edited {} frames", got.n_frames())),
            "{text}"
        );
        assert_eq!(got, expected, "{ext}: the whole edit cut");
    }
    let past = run(&[
        "edit",
        "--model",
        p(&model),
        p(&capture),
        "--translate",
        "0=1",
        "--out",
        p(&dir.path().join("none.trc")),
        "--start",
        "99999",
    ]);
    let err = String::from_utf8_lossy(&past.stderr);
    assert!(!past.status.success(), "{err}");
    assert!(
        err.contains("--start/--end keep no frame: the take has frames"),
        "{err}"
    );
    assert!(
        !dir.path().join("none.trc").exists(),
        "no file for an empty range"
    );
}

/// The emotion edits (the live low-pass, which carries state from frame to frame, and the
/// take-mean offset, which needs the whole take's mean) from every format, in blocks that cut
/// the range anywhere: the whole edit cut, every time.
#[test]
fn ranged_emotion_edits_are_the_whole_edit_cut_in_any_block_size() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = p(dir.path());
    let synth = [
        "synth",
        "--out",
        d,
        "--sentences",
        "3",
        "--seed",
        "9",
        "--head-motion",
    ];
    ok(&[&synth[..], &["--force"]].concat());
    let (manifest, model_path) = (dir.path().join("session.toml"), dir.path().join("m.json"));
    let (mp, mf) = (p(&model_path), p(&manifest));
    ok(&["train", "--manifest", mf, "--out", mp, "--components", "8"]);
    let report = dir.path().join("report");
    ok(&[
        "analyze",
        "--model",
        mp,
        "--manifest",
        mf,
        "--out",
        p(&report),
        "--write-model",
    ]);
    let model = offline::load_model(&model_path).expect("model");
    let take = replay::load(&dir.path().join("s01_happy.c3d")).expect("synth take");
    let (start, end) = (
        Some(FrameOrTime::Seconds(0.25)),
        Some(FrameOrTime::Frame(take.first_frame + 99)),
    );
    let live = EditRequest {
        to_emotion: Some("frustrated".into()),
        amount: 0.8,
        lowpass_s: Some(0.5),
        start,
        end,
        ..EditRequest::default()
    };
    let mean = EditRequest {
        lowpass_s: None,
        ..live.clone()
    };
    for ext in ["c3d", "trc", "csv"] {
        let input = dir.path().join(format!("in.{ext}"));
        replay::save(&input, &take).expect("input written");
        let loaded = offline::load_take(&input).expect("input");
        for request in [&live, &mean] {
            let whole = edit_take(&model, &model_path, &loaded, &input, request).expect("whole");
            let expected = dir.path().join(format!("expected.{ext}"));
            replay::save(&expected, &cut(&whole, start, end)).expect("written");
            let expected = replay::load(&expected).expect("reads");
            let out = dir.path().join(format!("out.{ext}"));
            for block in [1, 7, 64, 100_000] {
                let m = (model_path.as_path(), &model);
                // Some of the first pass's projections kept (the rest made again), or all of
                // them (the take is not read again).
                let keep = if block % 2 == 1 {
                    4096
                } else {
                    streamed::KEEP_BYTES
                };
                let streaming = (block, keep);
                let s = edit::edit_file(m, (&input, LIMIT), request, &out, streaming, &mut Silent)
                    .expect("ranged edit");
                assert_eq!(s.frames, expected.n_frames(), "{ext}, blocks of {block}");
                let got = replay::load(&out).expect("reads");
                assert_eq!(got, expected, "{ext}, blocks of {block}: {request:?}");
            }
        }
    }
}
