use std::net::SocketAddr;
use std::sync::Arc;

use ica_core::edit::FrameEdit;
use protocol::{
    decode_frame_into, encode_frame_into, encode_labels_into, messages, FrameBuf, Labels,
};

use super::*;
use crate::engine::frame::FrameProcessor;
use crate::synthetic::{frame_into, random_model};

const MARKERS: usize = 12;

fn peer() -> SocketAddr {
    "127.0.0.1:5000".parse().expect("addr")
}

fn labels_datagram(model: &IcaModel, reversed: bool) -> Vec<u8> {
    let mut names = model.labels().to_vec();
    if reversed {
        names.reverse();
    }
    let mut out = Vec::new();
    encode_labels_into(
        &Labels {
            layout_id: 1,
            names,
        },
        &mut out,
    )
    .expect("valid labels");
    out
}

fn frame_datagram(xyz: &[f32], n: i32) -> Vec<u8> {
    let mut buf = FrameBuf::with_max_markers(MARKERS);
    buf.set_frame(n, i64::from(n) * 8333, xyz).expect("finite");
    let mut out = Vec::new();
    encode_frame_into(&buf, &mut out).expect("finite");
    out
}

/// Decoded positions of every compact frame the pipeline emits.
fn run(p: &mut Pipeline, datagrams: &[Vec<u8>]) -> Vec<(i32, Vec<f32>)> {
    let mut got = Vec::new();
    for d in datagrams {
        p.handle_datagram(peer(), d, &mut |e| {
            let msg = messages(e.compact, &protocol::Limits::default())
                .expect("well-formed")
                .find(|m| m.address == protocol::address::FRAME)
                .expect("the bundle holds the frame");
            let mut buf = FrameBuf::new();
            decode_frame_into(msg.bytes, &mut buf).expect("valid frame");
            got.push((e.frame_number, buf.positions().to_vec()));
        });
    }
    got
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
    let mut datagrams = vec![labels_datagram(&model, false)];
    let mut frames = Vec::new();
    for f in 0..50 {
        frame_into(&model, f, &mut xyz);
        frames.push(xyz.clone());
        datagrams.push(frame_datagram(&xyz, f as i32));
    }
    let got = run(&mut p, &datagrams);
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
fn labels_map_reordered_sources_and_bad_or_stale_frames_are_counted() {
    let model = Arc::new(random_model(MARKERS, 4, 3));
    let mut p = Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default());
    let mut xyz = vec![0.0; MARKERS * 3];
    frame_into(&model, 0, &mut xyz);
    let mut reversed = xyz.clone();
    for (i, c) in xyz.chunks_exact(3).enumerate() {
        let j = MARKERS - 1 - i;
        reversed[j * 3..j * 3 + 3].copy_from_slice(c);
    }
    let datagrams = vec![
        frame_datagram(&reversed, 0),
        labels_datagram(&model, true),
        frame_datagram(&reversed, 1),
        vec![1, 2, 3],
        frame_datagram(&reversed, 1),
        frame_datagram(&reversed, 0),
        frame_datagram(&reversed, 2),
    ];
    let got = run(&mut p, &datagrams);
    assert_eq!(got.iter().map(|g| g.0).collect::<Vec<_>>(), vec![1, 2]);
    // Model order out, whatever the source order: the first marker is model marker 0.
    assert!(
        (got[0].1[0] - xyz[0]).abs() < 0.5,
        "{} vs {}",
        got[0].1[0],
        xyz[0]
    );
    let c = &p.counters;
    assert_eq!(c.dropped_no_layout, 1);
    assert_eq!((c.dropped_duplicate, c.dropped_stale), (1, 1));
    assert_eq!(c.bad_total(), 1);
    assert_eq!((c.frames_in, c.frames_out), (5, 2));
}

#[test]
fn a_model_swap_keeps_the_stream_order_and_settings() {
    let model = Arc::new(random_model(MARKERS, 4, 3));
    let mut p = Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default());
    p.handle_edit(&Control::Target("happy".into()))
        .expect("known");
    let mut xyz = vec![0.0; MARKERS * 3];
    frame_into(&model, 0, &mut xyz);
    assert_eq!(
        run(
            &mut p,
            &[labels_datagram(&model, false), frame_datagram(&xyz, 0)]
        )
        .len(),
        1
    );
    p.set_model(Arc::new(random_model(MARKERS, 4, 9)));
    assert_eq!(run(&mut p, &[frame_datagram(&xyz, 1)]).len(), 1);
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
        p.handle_datagram(peer, &labels_datagram(&model, false), &mut |_| {});
        for n in numbers {
            p.handle_datagram(peer, &frame_datagram(&xyz, n), &mut |_| {});
        }
    }
    let status = p.stream_status();
    let counts: Vec<_> = status
        .iter()
        .map(|s| (s.key.source, s.frames, s.duplicates, s.stale))
        .collect();
    assert_eq!(counts, vec![(a, 3, 0, 0), (b, 2, 1, 1)]);
}

/// Issue 16: a source's `/mocap/timecode` reaches the emitted frame and rides in the compact
/// and components outputs; a frame without one has none.
#[test]
fn the_source_timecode_travels_with_its_frame() {
    use protocol::{
        decode_timecode, encode_frame_timed_into, CaptureClock, FrameTime, Smpte, TimecodeRate,
    };
    let model = Arc::new(random_model(MARKERS, 4, 5));
    let mut p = Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default());
    p.set_wanted(profile_bit(Profile::Compact) | profile_bit(Profile::Components));
    let mut xyz = vec![0.0; MARKERS * 3];
    frame_into(&model, 0, &mut xyz);
    let time = FrameTime {
        timecode: Some(Smpte::from_frame_count(1_800, TimecodeRate::DF_29_97)),
        clock: CaptureClock::Utc,
    };
    let mut buf = FrameBuf::with_max_markers(MARKERS);
    buf.set_frame(1, 99, &xyz).expect("finite");
    let mut timed = Vec::new();
    encode_frame_timed_into(&buf, &time, &mut timed).expect("finite");
    p.handle_datagram(peer(), &labels_datagram(&model, false), &mut |_| {});
    let mut got = Vec::new();
    for d in [timed, frame_datagram(&xyz, 2)] {
        p.handle_datagram(peer(), &d, &mut |e| {
            let carried = |bytes: &[u8]| {
                messages(bytes, &protocol::Limits::default())
                    .expect("well-formed")
                    .find(|m| m.address == protocol::address::TIMECODE)
                    .map(|m| decode_timecode(m.bytes).expect("valid"))
            };
            got.push((*e.time, carried(e.compact), carried(e.components)));
        });
    }
    assert_eq!(got[0], (time, Some(time), Some(time)));
    assert_eq!(got[1], (FrameTime::default(), None, None));
    assert_eq!(
        time.timecode.map(|t| t.to_string()).as_deref(),
        Some("00:01:00;02.0")
    );
}

/// Sources that went quiet give their slot back: a stage whose bridge restarts from a new port
/// each time must not run out of sources for good (it did after 64 such restarts).
#[test]
fn quiet_sources_are_forgotten_and_their_slots_taken_again() {
    let model = Arc::new(random_model(MARKERS, 4, 9));
    let mut p = Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default());
    let mut xyz = vec![0.0; MARKERS * 3];
    frame_into(&model, 0, &mut xyz);
    let labels = labels_datagram(&model, false);
    let source =
        |i: usize| -> SocketAddr { format!("127.0.0.2:{}", 6000 + i).parse().expect("addr") };
    let mut out = 0;
    let mut send = |p: &mut Pipeline, who: SocketAddr, n: i32| {
        p.handle_datagram(who, &labels, &mut |_| {});
        p.handle_datagram(who, &frame_datagram(&xyz, n), &mut |_| out += 1);
    };
    for i in 0..MAX_SOURCES {
        send(&mut p, source(i), 1);
    }
    assert_eq!(p.stream_count(), MAX_SOURCES);
    // One more is refused with a reason, and its frames have no layout.
    let late = source(MAX_SOURCES);
    send(&mut p, late, 1);
    let refusal = p.take_refusal().expect("told why");
    assert_eq!(refusal.to, late);
    assert!(refusal.why.contains("64 sources"), "{}", refusal.why);
    assert_eq!(p.counters.dropped_no_layout, 1);
    // Source 0 keeps sending; the others are silent through the sweeps.
    for sweep in 0..QUIET_SWEEPS {
        assert!(
            p.forget_quiet_sources().is_empty(),
            "sweep {sweep}: forgotten too soon"
        );
        send(&mut p, source(0), 2 + sweep as i32);
    }
    let gone = p.forget_quiet_sources();
    assert_eq!(gone.len(), MAX_SOURCES - 1);
    assert!(!gone.contains(&source(0)));
    assert_eq!(p.stream_count(), 1);
    // The late source is taken now, and its frames go out.
    let before = p.counters.frames_out;
    send(&mut p, late, 1);
    assert!(p.take_refusal().is_none());
    assert_eq!(p.counters.frames_out, before + 1);
    assert_eq!(p.stream_count(), 2);
    // A forgotten source that comes back is taken again from its labels.
    send(&mut p, source(5), 1);
    assert_eq!(p.stream_count(), 3);
    assert!(out > MAX_SOURCES);
}

/// A source whose markers are none of the model's hears why its frames make no stream (it was
/// dropped in silence, counted in `/status` only).
#[test]
fn a_source_with_none_of_the_models_markers_hears_why() {
    let model = Arc::new(random_model(MARKERS, 4, 11));
    let mut p = Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default());
    let names: Vec<String> = (0..MARKERS).map(|i| format!("other{i}")).collect();
    let mut labels = Vec::new();
    encode_labels_into(
        &Labels {
            layout_id: 3,
            names,
        },
        &mut labels,
    )
    .expect("valid labels");
    let xyz = vec![1.0; MARKERS * 3];
    p.handle_datagram(peer(), &labels, &mut |_| {});
    assert!(p.take_refusal().is_none(), "labels alone are fine");
    p.handle_datagram(peer(), &frame_datagram(&xyz, 1), &mut |_| {
        panic!("no stream")
    });
    let refusal = p.take_refusal().expect("told why");
    assert_eq!(refusal.to, peer());
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
    for (n, frame) in [(1, &xyz), (2, &one), (3, &none), (4, &xyz)] {
        p.handle_datagram(peer(), &labels_datagram(&model, false), &mut |_| {});
        p.handle_datagram(peer(), &frame_datagram(frame, n), &mut |e| {
            let msg = messages(e.compact, &protocol::Limits::default())
                .expect("well-formed")
                .find(|m| m.address == protocol::address::FRAME)
                .expect("the frame");
            let mut buf = FrameBuf::new();
            decode_frame_into(msg.bytes, &mut buf).expect("valid frame");
            got.push(buf);
        });
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
