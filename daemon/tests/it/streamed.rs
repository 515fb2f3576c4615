//! Issue 18: `project` and `edit` streamed in blocks of frames write exactly what the
//! whole-take path writes, whatever the block size, input and output format, across gaps,
//! glitches and held head poses that carry state from one block into the next.

use std::path::{Path, PathBuf};

use crate::common::{ok, p};
use daemon::offline::edit::{self, edit_take, EditRequest};
use daemon::offline::progress::{Progress, Silent};
use daemon::offline::{self, streamed};
use ica_core::model::IcaModel;
use replay::{Format, Take};

const LIMIT: u64 = 1 << 30;

/// synth (head motion) -> train -> analyze --write-model: a model with stabilisation, glitch
/// limits and an emotion space.
fn model(dir: &Path) -> (PathBuf, IcaModel) {
    let d = p(dir);
    ok(&[
        "synth",
        "--out",
        d,
        "--sentences",
        "3",
        "--seed",
        "9",
        "--head-motion",
        "--force",
    ]);
    let (manifest, model) = (dir.join("session.toml"), dir.join("model.json"));
    ok(&[
        "train",
        "--manifest",
        p(&manifest),
        "--out",
        p(&model),
        "--components",
        "8",
    ]);
    let report = dir.join("report");
    let (m, r) = (p(&model), p(&report));
    ok(&[
        "analyze",
        "--model",
        m,
        "--manifest",
        p(&manifest),
        "--out",
        r,
        "--write-model",
    ]);
    let loaded = offline::load_model(&model).expect("model");
    assert!(!loaded.emotion().space_components().is_empty(), "analysed");
    (model, loaded)
}

/// A synthetic take with what carries state across frames: a gap across a block boundary,
/// the head reference gone for a few frames (the pose is held), a one-frame spike (a glitch).
fn damaged(dir: &Path, model: &IcaModel) -> Take {
    let mut take = replay::load(&dir.join("s01_frustrated.c3d")).expect("synth take");
    let n = take.n_markers();
    let head = model.capture().head.as_ref().expect("a stabilised model");
    let label = |m: usize| take.marker_index(&model.labels()[m]).expect("model label");
    let reference: Vec<usize> = head.markers.iter().map(|&m| label(m)).collect();
    for f in 5..20 {
        take.missing[f * n + 3] = true;
    }
    for f in 30..34 {
        for &m in &reference {
            take.missing[f * n + m] = true;
        }
    }
    take.positions[(13 * n + 10) * 3] += 40.0;
    take
}

fn save_as(dir: &Path, take: &Take, name: &str) -> PathBuf {
    let path = dir.join(name);
    replay::save(&path, take).expect("input written");
    path
}

fn read(path: &Path) -> Vec<u8> {
    std::fs::read(path).expect("output written")
}

/// Whole-take edit and streamed edit of `input` into `format`; equal bytes, or equal takes
/// when the streamed file has a padded header (a count the input header did not give).
fn check_edit(model: (&Path, &IcaModel), input: &Path, request: &EditRequest, format: Format) {
    let out = input.with_file_name(format!("out.{}", format.extension()));
    let take = offline::load_take(input).expect("input");
    let whole = edit_take(model.1, model.0, &take, input, request).expect("whole edit");
    let expected = input.with_file_name(format!("whole.{}", format.extension()));
    replay::save(&expected, &whole).expect("whole written");
    let exact = Format::from_path(input) != Some(Format::Csv) || format == Format::Csv;
    // A two-pass edit takes the first pass's projections back up to a budget, then carries
    // on from the state the first pass had there: the budgets end inside the gap (about 11
    // frames), after the glitch, inside the held pose (about 31), and never (all kept).
    let keep = streamed::KEEP_BYTES;
    for (block, keep) in [(1, keep), (7, 2000), (100_000, 5600), (7, 0)] {
        let streaming = (block, keep);
        let s = edit::edit_file(model, (input, LIMIT), request, &out, streaming, &mut Silent)
            .expect("streamed edit");
        assert_eq!(s.frames, take.n_frames());
        assert!(s.notices.is_empty(), "{:?}", s.notices);
        let what =
            format!("{input:?} -> {format:?} in blocks of {block}, {keep} B kept: {request:?}");
        if exact {
            assert!(read(&out) == read(&expected), "{what}");
        } else {
            assert_eq!(replay::load(&out).expect("readable"), whole, "{what}");
        }
    }
}

#[test]
fn streamed_edits_write_what_the_whole_take_edit_writes() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (model_path, model) = model(dir.path());
    let take = damaged(dir.path(), &model);
    let raw = EditRequest {
        translate: vec![(0, 1.5)],
        gain: vec![(1, 0.7)],
        amount: 1.0,
        ..EditRequest::default()
    };
    let mean = EditRequest {
        to_emotion: Some("happy".into()),
        amount: 0.7,
        ..raw.clone()
    };
    let blend_keep_gaps = EditRequest {
        to_emotion: Some("happy:0.5,neutral:0.5".into()),
        keep_gaps: true,
        ..mean.clone()
    };
    let live = EditRequest {
        lowpass_s: Some(0.5),
        ..mean.clone()
    };
    let m = (model_path.as_path(), &model);
    let c3d = save_as(dir.path(), &take, "in.c3d");
    for request in [&raw, &mean, &blend_keep_gaps, &live] {
        for format in [Format::C3d, Format::Trc, Format::Csv] {
            check_edit(m, &c3d, request, format);
        }
    }
    for input in ["in.trc", "in.csv"] {
        let input = save_as(dir.path(), &take, input);
        for format in [Format::C3d, Format::Trc, Format::Csv] {
            check_edit(m, &input, &mean, format);
        }
    }
    // With every frame's projection kept and nothing else of the take needed, the edit pass
    // does not read the take: emptied as that pass begins, it is not missed. With
    // `--keep-gaps` the pass reads the take again and finds it emptied.
    let out = dir.path().join("kept.c3d");
    let whole = edit_take(&model, &model_path, &take, &c3d, &mean).expect("whole edit");
    let streaming = (7, streamed::KEEP_BYTES);
    let mut emptied = EmptiesOnEditing(c3d.clone());
    edit::edit_file(m, (&c3d, LIMIT), &mean, &out, streaming, &mut emptied)
        .expect("the take is not read again");
    assert_eq!(replay::load(&out).expect("readable"), whole);
    let c3d = save_as(dir.path(), &take, "in.c3d");
    let mut emptied = EmptiesOnEditing(c3d.clone());
    edit::edit_file(
        m,
        (&c3d, LIMIT),
        &blend_keep_gaps,
        &out,
        streaming,
        &mut emptied,
    )
    .expect_err("the take is read again, and was emptied");
    // A CSV without `rate_hz` is read whole (its rate needs every row) and edited in blocks.
    let text = std::fs::read_to_string(dir.path().join("in.csv")).expect("csv");
    let no_rate = dir.path().join("no_rate.csv");
    std::fs::write(&no_rate, text.split_once('\n').expect("comment line").1).expect("written");
    check_edit(m, &no_rate, &mean, Format::Trc);
}

/// Empties the input file as the edit pass begins.
struct EmptiesOnEditing(PathBuf);

impl Progress for EmptiesOnEditing {
    fn step(&mut self, name: &str, _unit: &'static str, _total: Option<u64>) {
        if name == "editing" {
            std::fs::write(&self.0, b"").expect("emptied");
        }
    }

    fn advance(&mut self, _n: u64) {}
}

/// `project`'s CSV of the whole take, as the whole-take path computes it.
fn whole_projection(model: &IcaModel, input: &Path) -> String {
    use std::fmt::Write as _;
    let take = offline::load_take(input).expect("input");
    let map = offline::match_take(model, &take, input).expect("labels");
    let projected =
        offline::project_take(model, &offline::to_model_order(&take, &map)).expect("projected");
    let mut text = String::from("frame,time");
    for k in 0..projected.m {
        write!(text, ",c{k}").expect("string");
    }
    text.push('\n');
    for (f, row) in projected.u.chunks_exact(projected.m).enumerate() {
        let number = take.first_frame + f as i64;
        write!(text, "{number},{:.6}", take.time_of(f)).expect("string");
        for v in row {
            write!(text, ",{v}").expect("string");
        }
        text.push('\n');
    }
    text
}

#[test]
fn streamed_projection_is_the_whole_take_projection_and_failures_leave_no_file() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (_, model) = model(dir.path());
    let take = damaged(dir.path(), &model);
    let out = dir.path().join("u.csv");
    for name in ["in.c3d", "in.trc", "in.csv"] {
        let input = save_as(dir.path(), &take, name);
        let expected = whole_projection(&model, &input);
        for block in [1, 7, 100_000] {
            let s = streamed::project_file(&model, (&input, LIMIT), &out, block, &mut Silent)
                .expect("projected");
            assert_eq!(s.frames, take.n_frames());
            assert!(s.notices.is_empty(), "{:?}", s.notices);
            let got = std::fs::read_to_string(&out).expect("written");
            assert!(got == expected, "{name} in blocks of {block}");
        }
    }
    // A take cut half way: an error naming the file, and neither the output nor a partial
    // file left behind.
    std::fs::remove_file(&out).expect("removable");
    let bytes = read(&dir.path().join("in.trc"));
    let cut = dir.path().join("cut.trc");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).expect("written");
    let e = streamed::project_file(&model, (&cut, LIMIT), &out, 7, &mut Silent)
        .expect_err("a truncated take");
    assert!(format!("{e:#}").contains("cut.trc"), "{e:#}");
    let edited = dir.path().join("e.c3d");
    let request = EditRequest {
        translate: vec![(0, 1.0)],
        ..EditRequest::default()
    };
    let m = (dir.path().join("model.json"), &model);
    let e = edit::edit_file(
        (&m.0, m.1),
        (&cut, LIMIT),
        &request,
        &edited,
        (7, streamed::KEEP_BYTES),
        &mut Silent,
    )
    .expect_err("a truncated take");
    assert!(format!("{e:#}").contains("cut.trc"), "{e:#}");
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .expect("dir")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.starts_with('.') || n == "u.csv" || n == "e.c3d")
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

#[test]
fn a_take_whose_markers_or_rate_differ_from_the_model_is_named_in_the_notices() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (model_path, model) = model(dir.path());
    let mut take = damaged(dir.path(), &model).resampled(60.0);
    let renamed = take.labels[4].clone();
    take.labels[4] = "Renamed".into();
    let input = save_as(dir.path(), &take, "renamed.c3d");
    let want = [
        format!(
            "lacks 1 of the model's {} markers ({renamed}); has 1 marker the model does not have (Renamed)",
            model.markers()
        ),
        format!("is at 60 Hz, the model at {} Hz", model.rate_hz()),
    ];
    let out = dir.path().join("u.csv");
    let s =
        streamed::project_file(&model, (&input, LIMIT), &out, 100, &mut Silent).expect("projected");
    assert_eq!(s.notices, want);
    // A mean-based edit keeps every projection of the first pass, yet reads the take again
    // for the marker the model lacks, which the output carries unchanged.
    let request = EditRequest {
        translate: vec![(0, 1.0)],
        to_emotion: Some("happy".into()),
        amount: 0.5,
        ..EditRequest::default()
    };
    let edited = dir.path().join("e.c3d");
    let s = edit::edit_file(
        (&model_path, &model),
        (&input, LIMIT),
        &request,
        &edited,
        (100, streamed::KEEP_BYTES),
        &mut Silent,
    )
    .expect("edited");
    assert_eq!(s.notices, want);
    let whole = edit_take(&model, &model_path, &take, &input, &request).expect("whole edit");
    let got = replay::load(&edited).expect("readable");
    assert_eq!(got.labels.last().map(String::as_str), Some("Renamed"));
    assert_eq!(got, whole);
}
