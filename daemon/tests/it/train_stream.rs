//! Issue 18: streaming training gives the in-memory model on sessions small enough to hold,
//! the same model on one thread or two, and shows its progress in a pipe. Real captures
//! (Facial-Sing: gaps, label swaps, head rig; AnimFace: a moving head), fixtures in the repo.

use std::path::{Path, PathBuf};

use daemon::offline::progress::Silent;
use daemon::offline::training::{self, StreamOptions, TrainOptions, Trained};
use daemon::offline::{self, LoadedTake, TakeInput};

use crate::common::p as s;

fn fixture(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

fn facial_sing() -> Vec<PathBuf> {
    vec![fixture("../replay/tests/fixtures/Facial-Sing.c3d")]
}

fn animface() -> Vec<PathBuf> {
    ["JawMoCap.c3d", "EyebrowsMoCap.c3d"]
        .iter()
        .map(|f| fixture(&format!("tests/fixtures/animface/{f}")))
        .collect()
}

fn in_memory(paths: &[PathBuf], options: &TrainOptions) -> Trained {
    let takes: Vec<LoadedTake> = paths
        .iter()
        .map(|p| LoadedTake {
            path: p.clone(),
            take: offline::load_take(p).expect("fixture loads"),
        })
        .collect();
    training::train(&takes, options, &mut |_| {}).expect("trains in memory")
}

/// Files used whole.
fn inputs(paths: &[PathBuf]) -> Vec<TakeInput> {
    paths.iter().cloned().map(TakeInput::from).collect()
}

fn streamed(paths: &[PathBuf], options: &TrainOptions, threads: usize) -> Trained {
    let stream = StreamOptions {
        threads,
        always_stream: true,
        hold_frames: None,
    };
    training::train_files(&inputs(paths), options, &stream, &mut Silent).expect("trains streaming")
}

/// The models agree: the same preparation and PCA, and mixing columns within `tol` of the
/// largest loading (f32 spill and rounding differ; ICA order and sign are fixed by the
/// convention, so columns are compared as they are).
fn assert_same_model(a: &Trained, b: &Trained, tol: f64) {
    let (ma, mb) = (&a.model, &b.model);
    assert_eq!(ma.labels(), mb.labels());
    assert_eq!(ma.components(), mb.components());
    let (ra, rb) = (ma.report(), mb.report());
    assert_eq!(ra.frames_used, rb.frames_used);
    assert_eq!(ra.frames_total, rb.frames_total);
    assert_eq!(ma.capture(), mb.capture(), "capture settings differ");
    assert_eq!(a.gaps, b.gaps);
    assert_eq!(a.data.glitches, b.data.glitches);
    assert_eq!(a.data.residual_summary, b.data.residual_summary);
    for (x, y) in ra.eigenvalues.iter().zip(&rb.eigenvalues) {
        assert!(
            (x - y).abs() <= 1e-9 * ra.eigenvalues[0],
            "eigenvalue {x} vs {y}"
        );
    }
    let scale = ma.mixing().amax();
    let diff = (ma.mixing() - mb.mixing()).amax();
    assert!(
        diff <= tol * scale,
        "mixing differs by {diff:e} (scale {scale})"
    );
    let (qa, qb) = (ma.quality(), mb.quality());
    for (x, y) in qa
        .residual_by_marker_mm
        .iter()
        .zip(&qb.residual_by_marker_mm)
    {
        assert!((x - y).abs() < 1e-3, "residual {x} vs {y}");
    }
    assert_eq!(qa.head, qb.head);
    assert_eq!(qa.warnings.len(), qb.warnings.len(), "{qa:?}\n{qb:?}");
}

#[test]
fn issue_18_streaming_matches_in_memory_on_facial_sing() {
    let options = TrainOptions::default();
    let paths = facial_sing();
    let (a, b) = (in_memory(&paths, &options), streamed(&paths, &options, 2));
    assert!(a.gaps.frames > 0, "Facial-Sing has gaps to fill");
    assert_same_model(&a, &b, 1e-4);
}

#[test]
fn issue_18_streaming_matches_in_memory_on_animface_and_threads_do_not_change_it() {
    let mut options = TrainOptions::default();
    options.params = options.params.clone().n_components(12);
    options.noise_floor = false;
    let paths = animface();
    let a = in_memory(&paths, &options);
    let one = streamed(&paths, &options, 1);
    let two = streamed(&paths, &options, 2);
    assert_same_model(&a, &two, 1e-4);
    assert_eq!(
        one.model.mixing(),
        two.model.mixing(),
        "threads changed the model"
    );
    assert_eq!(one.model.mean(), two.model.mean());
}

#[test]
fn issue_18_train_shows_progress_in_a_pipe() {
    let dir = tempfile::tempdir().expect("temp dir");
    let model = dir.path().join("model.json");
    let take = facial_sing().remove(0);
    let args = [
        "train",
        "--stream",
        "--threads",
        "1",
        "--out",
        s(&model),
        s(&take),
    ];
    crate::common::shows_progress(
        &args,
        &[
            "train: reading takes done: 1 takes in ",
            "train: statistics done: ",
            "train: whitening done: ",
            " FastICA restarts on ",
        ],
    );
    assert!(std::fs::metadata(&model).is_ok());
}

/// The first pass guesses a session's length from its first take's frames per byte and holds
/// nothing when the guess is well past the in-memory limit; a short session guessed long
/// (here the second take carries 400 markers the first does not, so its bytes say eleven
/// times its frames) is read again and trained in memory: the path depends on frames only.
#[test]
fn a_short_session_guessed_long_from_its_file_sizes_still_trains_in_memory() {
    let dir = tempfile::tempdir().expect("temp dir");
    let sing = offline::load_take(&facial_sing()[0]).expect("fixture loads");
    let frames = 300;
    let mut first = replay::Take::new(sing.labels.clone(), sing.rate_hz, 1);
    let mut labels = sing.labels.clone();
    labels.extend((0..400).map(|i| format!("extra{i}")));
    let mut bulky = replay::Take::new(labels, sing.rate_hz, 1);
    for f in 0..frames {
        first.push_frame(sing.frame(f), sing.frame_missing(f));
        let g = frames + f;
        let mut xyz = sing.frame(g).to_vec();
        let mut missing = sing.frame_missing(g).to_vec();
        xyz.extend((0..400 * 3).map(|i| 1.0 + i as f32));
        missing.extend([false; 400]);
        bulky.push_frame(&xyz, &missing);
    }
    let paths = [dir.path().join("a.c3d"), dir.path().join("b.c3d")];
    replay::save(&paths[0], &first).expect("writes");
    replay::save(&paths[1], &bulky).expect("writes");
    let options = TrainOptions::default();
    let stream = StreamOptions {
        threads: 1,
        always_stream: false,
        hold_frames: Some(2 * frames),
    };
    let got =
        training::train_files(&inputs(&paths), &options, &stream, &mut Silent).expect("trains");
    let want = in_memory(&paths, &options);
    // The in-memory path on the same takes: the same numbers, not merely close ones.
    let apart = (got.model.mixing() - want.model.mixing()).amax();
    assert!(apart == 0.0, "streamed, not held: mixing {apart:e} apart");
    assert_eq!(got.model.mean(), want.model.mean());
}
