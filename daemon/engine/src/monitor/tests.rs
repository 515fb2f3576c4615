use std::net::SocketAddr;
use std::sync::Arc;

use protocol::{Control, FrameBuf, FrameTime};

use super::*;
use crate::input::SourceFrame;
use crate::output::{Each, Processed};
use crate::pipeline::{Pipeline, PipelineConfig};
use crate::streams::StreamKey;
use crate::synthetic::{frame_into, random_space_model};

const MARKERS: usize = 10;

#[test]
fn each_stream_gets_at_most_30_snapshots_a_second_whatever_the_jitter() {
    let mut tap = MonitorTap::new(30.0);
    let (mut a, mut b) = (0, 0);
    // Two streams at 120 Hz for 10 s, frames jittered by up to ±2 ms.
    for f in 0..1200u64 {
        let jitter = (f * 7919 % 4001) as i64 - 2000;
        let now = (f as i64 * 8333 + jitter).max(0) as u64;
        a += usize::from(tap.due(1, now));
        b += usize::from(tap.due(2, now + 300));
    }
    for n in [a, b] {
        assert!((295..=301).contains(&n), "{n} snapshots in 10 s");
    }
    // A slow source is taken every frame; a pause does not bank a burst for later.
    let mut tap = MonitorTap::new(30.0);
    assert!((0..10).all(|f| tap.due(3, f * 100_000)));
    let after_pause: usize = (0..120)
        .map(|f| usize::from(tap.due(3, 10_000_000 + f * 8333)))
        .sum();
    assert!((30..=31).contains(&after_pause), "{after_pause}");
}

#[test]
fn streams_beyond_the_cap_evict_the_longest_quiet_one() {
    let mut tap = MonitorTap::new(30.0);
    for id in 0..(MAX_SOURCES as i32 + 10) {
        assert!(
            tap.due(id, 1_000 + id as u64),
            "a new stream is due at once"
        );
    }
    assert_eq!(tap.due.len(), MAX_SOURCES);
}

#[test]
fn a_snapshot_holds_the_frame_in_and_out_its_gaps_components_and_edit_state() {
    let model = Arc::new(random_space_model(MARKERS, 4, 3));
    let mut p = Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default());
    for c in [
        Control::Ramp(0.0),
        Control::Target("happy".into()),
        Control::Amount(0.75),
    ] {
        p.handle_edit(&c).expect("valid edit");
    }
    let peer: SocketAddr = "127.0.0.1:7000".parse().expect("literal");
    let key = StreamKey {
        source: peer,
        layout_id: 0,
    };
    let labels: Arc<[String]> = model.labels().into();
    let mut xyz = vec![0.0; MARKERS * 3];
    let mut frame = FrameBuf::with_max_markers(MARKERS);
    let mut tap = MonitorTap::new(30.0);
    let mut taken = Vec::new();
    for n in 0..24 {
        frame_into(&model, n as usize, &mut xyz);
        frame.set_frame(n, 0, &xyz).expect("finite");
        frame.set_missing(2, true);
        let source = SourceFrame {
            key,
            performer: None,
            labels: &labels,
            frame: &frame,
            time: FrameTime::default(),
        };
        let mut out = 0;
        p.handle_frame(&source, &mut Each(|_: &Processed<'_>| out += 1));
        assert_eq!(out, 1, "the frame went out");
        let stream = p.stream(&key).expect("its stream");
        if let Some(s) = tap.handle_stream(n as u64 * 8333, stream) {
            taken.push(n);
            assert_eq!(s.frame_number, n);
            assert_eq!(s.stream_id, 0);
            for (m, (a, b)) in s.input.iter().zip(&xyz).enumerate() {
                if m / 3 != 2 {
                    assert_eq!(a, b, "the input as received");
                }
            }
            assert_eq!(s.output, stream.edited());
            assert_eq!(s.flags[2], FLAG_MISSING | FLAG_FILLED);
            assert!(s.flags.iter().enumerate().all(|(m, &f)| m == 2 || f == 0));
            assert_eq!(s.u_out, stream.components());
            assert_eq!(s.u_in.len(), 4);
            assert_ne!(s.u_in[0], s.u_out[0], "the emotion component moved");
            assert_eq!(s.u_in[1], s.u_out[1], "the others did not");
            assert_eq!((s.target.as_str(), s.amount_goal), ("happy", 0.75));
            assert_eq!((s.ramp_s, s.bypass, s.frames), (0.0, false, n as u64 + 1));
            assert!(Arc::ptr_eq(s.model.as_ref().expect("model"), &model));
        }
    }
    assert_eq!(
        taken,
        vec![0, 4, 8, 12, 16, 20],
        "every 4th frame at 120 Hz"
    );
}
