//! The live frame path allocates nothing once warm: 10,000 frames (109 markers, m = 20, some
//! markers missing, a live emotion edit gliding, every output profile encoded) through
//! `Pipeline::handle_datagram`, with the monitor page's tap active (a 30 Hz snapshot of the
//! stream published to the board as the processing thread does), counted by
//! allocation-counter's global allocator (no `unsafe` here: the workspace forbids it).

use std::net::SocketAddr;
use std::sync::Arc;

use daemon::engine::monitor::MonitorTap;
use daemon::engine::pipeline::{profile_bit, Pipeline, PipelineConfig};
use daemon::loopback::synthetic::{frame_into, random_model};
use daemon::serve::monitor::Board;
use protocol::{encode_frame_into, encode_labels_into, Control, FrameBuf, Labels, Profile};

const MARKERS: usize = 109;

#[test]
fn the_frame_path_does_not_allocate() {
    let model = Arc::new(random_model(MARKERS, 20, 4));
    let mut p = Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default());
    p.set_wanted(
        Profile::ALL
            .into_iter()
            .map(profile_bit)
            .fold(0, |a, b| a | b),
    );
    for c in [
        Control::Target("happy".into()),
        Control::Amount(0.8),
        Control::Alpha {
            component: 3,
            value: 1.0,
        },
        Control::Gain {
            component: 5,
            gain: 1.2,
        },
    ] {
        p.handle_edit(&c).expect("valid edit");
    }
    let peer: SocketAddr = "127.0.0.1:7000".parse().expect("literal");
    let mut labels = Vec::new();
    let names = model.labels().to_vec();
    encode_labels_into(
        &Labels {
            layout_id: 2,
            names,
        },
        &mut labels,
    )
    .expect("labels");
    p.handle_datagram(peer, &labels, &mut |_| {});
    // 16 distinct frames, every fourth with three markers missing.
    let mut buf = FrameBuf::with_max_markers(MARKERS);
    let datagrams: Vec<Vec<u8>> = (0..16)
        .map(|f| {
            let mut xyz = vec![0.0f32; MARKERS * 3];
            frame_into(&model, f, &mut xyz);
            if f % 4 == 0 {
                xyz[30..39].fill(f32::NAN);
            }
            buf.set_frame(0, 0, &xyz)
                .expect("finite or whole-marker NaN");
            let mut d = Vec::new();
            encode_frame_into(&buf, &mut d).expect("encodes");
            d
        })
        .collect();
    let mut datagrams = datagrams;
    let mut bytes_out = 0usize;
    // The monitor page open: its tap copies every 4th frame and publishes it.
    let board = Board::new();
    board.set_viewers(1);
    let mut tap = MonitorTap::new(30.0);
    let mut published = 0u64;
    let mut run = |p: &mut Pipeline, from: i32, count: i32, bytes: &mut usize| {
        for n in from..from + count {
            let d = &mut datagrams[n as usize % 16];
            // frame number after "/mocap/frame\0\0\0\0" and ",ihbb\0\0\0"
            d[24..28].copy_from_slice(&n.to_be_bytes());
            let mut last = None;
            p.handle_datagram(peer, d, &mut |e| {
                last = Some(e.key);
                *bytes += e.compact.len() + e.parts.len() + e.components.len()
            });
            let stream = last
                .and_then(|key| p.stream(&key))
                .expect("a frame went out");
            let now_us = n as u64 * 8_333;
            if let Some(snap) = tap.handle_stream(now_us, stream) {
                published += u64::from(board.publish(snap));
            }
        }
    };
    run(&mut p, 0, 200, &mut bytes_out);
    let info = allocation_counter::measure(|| run(&mut p, 200, 10_000, &mut bytes_out));
    assert_eq!(p.counters.frames_out, 10_200, "every frame processed");
    assert!(
        published >= 10_200 / 5,
        "the tap published {published} snapshots"
    );
    assert!(bytes_out > 10_200 * 1_000, "every profile encoded");
    assert_eq!(
        info.count_total, 0,
        "allocations in 10,000 frames: {info:?}"
    );
}
