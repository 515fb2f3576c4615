use std::net::SocketAddr;
use std::sync::Arc;

use ica_core::edit::FrameEdit;
use protocol::FrameBuf;

use super::*;
use crate::frame::FrameProcessor;
use crate::output::{Each, Processed};
use crate::synthetic::{frame_into, random_model};

const MARKERS: usize = 12;

fn peer() -> SocketAddr {
    "127.0.0.1:5000".parse().expect("addr")
}

/// A source as the engine sees it: its address, one layout, its labels shared.
struct Src {
    key: StreamKey,
    labels: Arc<[String]>,
    frame: FrameBuf,
    time: FrameTime,
}

impl Src {
    fn new(source: SocketAddr, model: &IcaModel, reversed: bool) -> Src {
        let mut names = model.labels().to_vec();
        if reversed {
            names.reverse();
        }
        Src::named(source, names)
    }

    fn named(source: SocketAddr, names: Vec<String>) -> Src {
        Src {
            key: StreamKey {
                source,
                layout_id: 1,
            },
            frame: FrameBuf::with_max_markers(names.len()),
            labels: names.into(),
            time: FrameTime::default(),
        }
    }

    /// Frame `n` (NaN markers missing) through `p`; the edited frames that came out.
    fn send(&mut self, p: &mut Pipeline, xyz: &[f32], n: i32) -> Vec<(i32, Vec<f32>)> {
        self.frame
            .set_frame(n, i64::from(n) * 8333, xyz)
            .expect("finite or missing");
        let frame = SourceFrame {
            key: self.key,
            performer: None,
            labels: &self.labels,
            frame: &self.frame,
            time: self.time,
        };
        let mut got = Vec::new();
        p.handle_frame(
            &frame,
            &mut Each(|e: &Processed<'_>| {
                got.push((e.frame_number(), e.output.positions().to_vec()));
            }),
        );
        got
    }
}

#[test]
fn live_alpha_and_gain_equal_the_offline_frame_path() {
    let model = Arc::new(random_model(MARKERS, 4, 7));
    let mut p = Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default());
    for c in [
        Control::Ramp(0.0),
        Control::Alpha {
            component: 1,
            value: 0.7,
        },
        Control::Gain {
            component: 2,
            gain: 1.5,
        },
    ] {
        p.handle_edit(&c).expect("valid edit");
    }
    let mut xyz = vec![0.0; MARKERS * 3];
    let mut src = Src::new(peer(), &model, false);
    let mut frames = Vec::new();
    let mut got = Vec::new();
    for f in 0..50 {
        frame_into(&model, f, &mut xyz);
        frames.push(xyz.clone());
        got.extend(src.send(&mut p, &xyz, f as i32));
    }
    assert_eq!(got.len(), 50);
    let mut proc = FrameProcessor::new(&model);
    let mut edit = FrameEdit::identity(4);
    edit.set_offset(1, 0.7).expect("in range");
    edit.set_gain(2, 1.5).expect("in range");
    let (mut u, mut out) = (vec![0.0; 4], vec![0.0; MARKERS * 3]);
    let missing = vec![false; MARKERS];
    for (f, (n, live)) in got.iter().enumerate() {
        assert_eq!(*n, f as i32);
        let prep = proc.project(&frames[f], &missing, &mut u).expect("sizes");
        edit.apply(&mut u).expect("sizes");
        proc.resynthesise(prep.pose.as_ref(), &u, &mut out)
            .expect("sizes");
        assert_eq!(live, &out, "frame {f}");
    }
}

#[test]
fn labels_map_reordered_sources_and_duplicate_or_stale_frames_are_counted() {
    let model = Arc::new(random_model(MARKERS, 4, 3));
    let mut p = Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default());
    let mut xyz = vec![0.0; MARKERS * 3];
    frame_into(&model, 0, &mut xyz);
    let mut reversed = xyz.clone();
    for (i, c) in xyz.chunks_exact(3).enumerate() {
        let j = MARKERS - 1 - i;
        reversed[j * 3..j * 3 + 3].copy_from_slice(c);
    }
    let mut src = Src::new(peer(), &model, true);
    let mut got = Vec::new();
    for n in [1, 1, 0, 2] {
        got.extend(src.send(&mut p, &reversed, n));
    }
    assert_eq!(got.iter().map(|g| g.0).collect::<Vec<_>>(), vec![1, 2]);
    // Model order out, whatever the source order: the first marker is model marker 0.
    assert!(
        (got[0].1[0] - xyz[0]).abs() < 0.5,
        "{} vs {}",
        got[0].1[0],
        xyz[0]
    );
    let c = &p.counters;
    assert_eq!((c.dropped_duplicate, c.dropped_stale), (1, 1));
    assert_eq!(c.frames_out, 2);
}

#[test]
fn a_model_swap_keeps_the_stream_order_and_settings() {
    let model = Arc::new(random_model(MARKERS, 4, 3));
    let mut p = Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default());
    p.handle_edit(&Control::Target("happy".into()))
        .expect("known");
    let mut xyz = vec![0.0; MARKERS * 3];
    frame_into(&model, 0, &mut xyz);
    let mut src = Src::new(peer(), &model, false);
    assert_eq!(src.send(&mut p, &xyz, 0).len(), 1);
    p.set_model(Arc::new(random_model(MARKERS, 4, 9)));
    assert_eq!(src.send(&mut p, &xyz, 1).len(), 1);
    assert_eq!(p.counters.model_swaps, 1);
    assert_eq!(
        p.handle_edit(&Control::Gain {
            component: 9,
            gain: 1.0
        }),
        Err(EditRefused::Component {
            index: 9,
            components: 4
        })
    );
}

#[test]
fn frame_order_is_counted_per_stream() {
    let model = Arc::new(random_model(MARKERS, 4, 5));
    let mut p = Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default());
    let mut xyz = vec![0.0; MARKERS * 3];
    frame_into(&model, 0, &mut xyz);
    let (a, b): (SocketAddr, SocketAddr) = (
        "127.0.0.1:7001".parse().expect("literal address"),
        "127.0.0.1:7002".parse().expect("literal address"),
    );
    for (peer, numbers) in [(a, vec![0, 1, 2]), (b, vec![0, 2, 1, 2])] {
        let mut src = Src::new(peer, &model, false);
        for n in numbers {
            src.send(&mut p, &xyz, n);
        }
    }
    let status = p.stream_status();
    let counts: Vec<_> = status
        .iter()
        .map(|s| (s.key.source, s.frames, s.duplicates, s.stale))
        .collect();
    assert_eq!(counts, vec![(a, 3, 0, 0), (b, 2, 1, 1)]);
}

/// Issue 16: the source's time of a frame reaches the processed frame; a frame without one
/// has none.
#[test]
fn the_source_time_travels_with_its_frame() {
    use protocol::{CaptureClock, Smpte, TimecodeRate};
    let model = Arc::new(random_model(MARKERS, 4, 5));
    let mut p = Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default());
    let mut xyz = vec![0.0; MARKERS * 3];
    frame_into(&model, 0, &mut xyz);
    let time = FrameTime {
        timecode: Some(Smpte::from_frame_count(1_800, TimecodeRate::DF_29_97)),
        irig: None,
        clock: CaptureClock::Utc,
    };
    let mut src = Src::new(peer(), &model, false);
    let mut got = Vec::new();
    for (n, t) in [(1, time), (2, FrameTime::default())] {
        src.time = t;
        src.frame.set_frame(n, 99, &xyz).expect("finite");
        let frame = SourceFrame {
            key: src.key,
            performer: None,
            labels: &src.labels,
            frame: &src.frame,
            time: src.time,
        };
        p.handle_frame(&frame, &mut Each(|e: &Processed<'_>| got.push(*e.time)));
    }
    assert_eq!(got, [time, FrameTime::default()]);
}

/// Streams that went quiet give their slot back: a stage whose bridge restarts from a new
/// port each time must not run out of streams for good (it did after 64 such restarts).
#[test]
fn quiet_streams_are_forgotten_and_their_slots_taken_again() {
    let model = Arc::new(random_model(MARKERS, 4, 9));
    let mut p = Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default());
    let mut xyz = vec![0.0; MARKERS * 3];
    frame_into(&model, 0, &mut xyz);
    let source =
        |i: usize| -> SocketAddr { format!("127.0.0.2:{}", 6000 + i).parse().expect("addr") };
    let mut sources: Vec<Src> = (0..=MAX_SOURCES)
        .map(|i| Src::new(source(i), &model, false))
        .collect();
    for src in &mut sources[..MAX_SOURCES] {
        assert_eq!(src.send(&mut p, &xyz, 1).len(), 1);
    }
    assert_eq!(p.stream_count(), MAX_SOURCES);
    // One more is refused with a reason.
    assert!(sources[MAX_SOURCES].send(&mut p, &xyz, 1).is_empty());
    let refusal = p.poll_refusal().expect("told why");
    assert_eq!(refusal.key.source, source(MAX_SOURCES));
    assert!(refusal.why.contains("64 streams"), "{}", refusal.why);
    // Source 0 keeps sending; the others are silent through the sweeps.
    for sweep in 0..QUIET_SWEEPS {
        assert!(
            p.forget_quiet_streams().is_empty(),
            "sweep {sweep}: forgotten too soon"
        );
        sources[0].send(&mut p, &xyz, 2 + sweep as i32);
    }
    let gone = p.forget_quiet_streams();
    assert_eq!(gone.len(), MAX_SOURCES - 1);
    assert!(!gone.iter().any(|k| k.source == source(0)));
    assert_eq!(p.stream_count(), 1);
    // The late source is taken now, and its frames go out.
    assert_eq!(sources[MAX_SOURCES].send(&mut p, &xyz, 1).len(), 1);
    assert!(p.poll_refusal().is_none());
    assert_eq!(p.stream_count(), 2);
    // A forgotten source that comes back is taken again, under its old id.
    let id = |p: &Pipeline, i: usize| {
        p.stream_status()
            .iter()
            .find(|s| s.key.source == source(i))
            .map(|s| s.id)
    };
    assert_eq!(sources[5].send(&mut p, &xyz, 1).len(), 1);
    assert_eq!((p.stream_count(), id(&p, 5)), (3, Some(5)));
}

/// A source whose markers are none of the model's hears why its frames make no stream (it was
/// dropped in silence, counted in `/status` only).
#[test]
fn a_source_with_none_of_the_models_markers_hears_why() {
    let model = Arc::new(random_model(MARKERS, 4, 11));
    let mut p = Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default());
    let names: Vec<String> = (0..MARKERS).map(|i| format!("other{i}")).collect();
    let xyz = vec![1.0; MARKERS * 3];
    let mut src = Src::named(peer(), names);
    assert!(src.send(&mut p, &xyz, 1).is_empty(), "no stream");
    let refusal = p.poll_refusal().expect("told why");
    assert_eq!(refusal.key.source, peer());
    assert!(
        refusal.why.starts_with("none of its 12 markers (other0, other1, other2, other3 and 8 more) is a marker of the model"),
        "{}",
        refusal.why
    );
    assert_eq!((p.counters.dropped_unmatched, p.stream_count()), (1, 0));
}

/// A frame with too few markers to estimate the face goes out as seen: the visible markers as
/// received, the others missing, not the last estimate passed off as every marker present.
#[test]
fn a_frame_too_occluded_to_estimate_goes_out_as_seen() {
    let model = Arc::new(random_model(MARKERS, 4, 13));
    let mut p = Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default());
    let mut xyz = vec![0.0; MARKERS * 3];
    frame_into(&model, 0, &mut xyz);
    // One marker seen: 3 channels for 4 components.
    let mut one = vec![f32::NAN; MARKERS * 3];
    one[6..9].copy_from_slice(&xyz[6..9]);
    let none = vec![f32::NAN; MARKERS * 3];
    let mut got = Vec::new();
    let mut src = Src::new(peer(), &model, false);
    for (n, frame) in [(1, &xyz), (2, &one), (3, &none), (4, &xyz)] {
        for (_, out) in src.send(&mut p, frame, n) {
            let mut buf = FrameBuf::with_max_markers(MARKERS);
            buf.set_frame(n, 0, &out).expect("finite or missing");
            got.push(buf);
        }
    }
    assert_eq!(got.len(), 4);
    let present = |b: &FrameBuf| (0..MARKERS).filter(|&i| !b.is_missing(i)).count();
    assert_eq!(present(&got[0]), MARKERS);
    assert_eq!(present(&got[1]), 1);
    assert!(!got[1].is_missing(2));
    assert_eq!(&got[1].positions()[6..9], &xyz[6..9]);
    assert_eq!(present(&got[2]), 0);
    assert_eq!(
        present(&got[3]),
        MARKERS,
        "the face comes back with the markers"
    );
}

/// Issue 37: a model trained on `HeadFront` meeting Motive's `Face:HeadFront` says to strip
/// the prefix, naming both sides.
#[test]
fn a_prefixed_source_is_told_to_strip_the_prefix() {
    let model = Arc::new(random_model(MARKERS, 4, 11));
    let mut p = Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default());
    let names: Vec<String> = model.labels().iter().map(|l| format!("Face:{l}")).collect();
    let xyz = vec![1.0; MARKERS * 3];
    let mut src = Src::named(peer(), names);
    assert!(src.send(&mut p, &xyz, 1).is_empty(), "no stream");
    let why = p.poll_refusal().expect("told why").why;
    assert!(why.contains("(Face:"), "the source's names: {why}");
    assert!(
        why.contains("whose markers start"),
        "the model's names: {why}"
    );
    assert!(
        why.contains("without the prefix \"Face:\" 12 of them are the model's")
            && why.contains("--natnet-names marker"),
        "{why}"
    );
}

/// Issue 37: without a model every frame passes through as received (the source's order,
/// missing markers missing), edits are refused naming `/model/load`, and a model loaded later
/// edits from the next frame, none dropped.
#[test]
fn without_a_model_frames_pass_through_until_one_is_set() {
    let model = Arc::new(random_model(MARKERS, 4, 21));
    let mut p = Pipeline::without_model(vec![], PipelineConfig::default());
    assert!(p.model().is_none());
    let refused = p.handle_edit(&Control::Target("happy".into()));
    assert_eq!(refused, Err(EditRefused::NoModel));
    assert!(EditRefused::NoModel.to_string().contains("/model/load"));
    let mut src = Src::new(peer(), &model, true);
    let mut xyz = vec![0.0; MARKERS * 3];
    for n in 0..5 {
        frame_into(&model, n as usize, &mut xyz);
        xyz[3..6].fill(f32::NAN);
        let got = src.send(&mut p, &xyz, n);
        assert_eq!(got.len(), 1, "frame {n}");
        assert_eq!(got[0].0, n, "same frame number");
        // The frame as sent: `send` builds it from `xyz` in the source's (reversed) order.
        let same = got[0]
            .1
            .iter()
            .zip(&xyz)
            .all(|(a, b)| a == b || (a.is_nan() && b.is_nan()));
        assert!(same, "frame {n} passes through unedited");
    }
    let status = p.stream_status();
    assert_eq!(
        (status[0].model_markers, status[0].unmatched_markers),
        (MARKERS, 0)
    );
    let stream = p.stream(&src.key).expect("the stream");
    assert_eq!(stream.labels(), &src.labels[..], "the source's labels");
    assert!(stream.components().is_empty());

    let other = random_model(MARKERS + 1, 4, 2);
    let mismatch = p
        .check_model(&other)
        .expect_err("the stream lacks a marker");
    assert!(mismatch.to_string().contains("lacks 1"), "{mismatch}");
    p.check_model(&model)
        .expect("the stream names every marker");
    p.set_model(Arc::clone(&model));
    p.handle_edit(&Control::Ramp(0.0)).expect("a model now");
    p.handle_edit(&Control::Target("happy".into()))
        .expect("known");
    p.handle_edit(&Control::Amount(1.0)).expect("in range");
    frame_into(&model, 5, &mut xyz);
    let got = src.send(&mut p, &xyz, 5);
    assert_eq!(got.len(), 1, "the next frame is not dropped");
    assert_eq!(p.stream(&src.key).expect("stream").labels(), model.labels());
    // Model order now: the source sent its markers reversed.
    let sent: Vec<f32> = xyz.chunks_exact(3).rev().flatten().copied().collect();
    let moved = got[0]
        .1
        .iter()
        .zip(&sent)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f32::max);
    assert!(moved > 0.1, "edited from the next frame ({moved} mm)");
    assert_eq!(p.counters.frames_out, 6);
}
