//! The NatNet frame path allocates nothing once the reused `FrameOfData` has grown:
//! allocation-counter's counting global allocator (it counts per thread) decides.

use std::time::{Duration, Instant};

use crate::natnet_fixtures::capture_frames;
use protocol::natnet::*;

/// A 109-marker face in a NatNet 4.1 frame, as a Motive markerset would stream it.
fn face_frame() -> Vec<u8> {
    let mut f = FrameOfData::default();
    let positions: Vec<[f32; 3]> = (0..109).map(|i| [i as f32 * 0.001, 1.6, 0.1]).collect();
    f.push_markerset("face", &positions);
    f.push_markerset("all", &positions);
    f.labeled_markers = (0..109)
        .map(|i| LabeledMarker {
            id: 1 << 16 | i,
            position: positions[i as usize],
            ..LabeledMarker::default()
        })
        .collect();
    let mut out = Vec::new();
    encode_frame_into(&f, NatNetVersion::V4_1, &mut out).expect("encodable");
    out
}

#[test]
fn decoding_10_000_frames_allocates_nothing() {
    let real = capture_frames();
    let face = face_frame();
    let mut frame = FrameOfData::default();
    let mut mm = Vec::with_capacity(109 * 3);
    let t0 = Instant::now();
    let mut client = Client::new(ClientConfig::default(), t0);
    // warm-up: grow every list to its steady size, connect the client and give it model defs
    decode_frame_into(&face, NatNetVersion::V4_1, &mut frame).expect("valid");
    decode_frame_into(&real[0], NatNetVersion::V3_0, &mut frame).expect("valid");
    let mut info = Vec::new();
    encode_server_info_into(
        &ServerInfo {
            app_name: "Motive".into(),
            app_version: [3, 1, 0, 0],
            natnet_version: NatNetVersion::V4_1,
            connection: None,
        },
        &mut info,
    )
    .expect("encodable");
    client
        .handle_datagram(t0, Channel::Command, &info)
        .expect("server info");
    let defs = ModelDefs {
        markersets: vec![
            MarkersetDef {
                name: "face".into(),
                marker_names: Vec::new(),
            },
            MarkersetDef {
                name: "all".into(),
                marker_names: Vec::new(),
            },
        ],
        ..ModelDefs::default()
    };
    let mut md = Vec::new();
    encode_model_defs_into(&defs, NatNetVersion::V4_1, &mut md).expect("encodable");
    client
        .handle_datagram(t0, Channel::Command, &md)
        .expect("model defs");
    while client.poll_event().is_some() {}
    while client.poll_transmit().is_some() {}

    let info = allocation_counter::measure(|| {
        for i in 0..10_000u32 {
            let now = t0 + Duration::from_micros(u64::from(i) * 8_333);
            if i % 2 == 0 {
                let incoming = client
                    .handle_datagram(now, Channel::Data, &face)
                    .expect("frame");
                assert_eq!(incoming, Incoming::Frame);
                let v = client.frame_version().expect("connected");
                decode_frame_into(&face, v, &mut frame).expect("valid");
                client.handle_frame(now, &frame);
                positions_mm_into(frame.markerset(0).expect("face").positions, &mut mm);
            } else {
                let d = &real[i as usize % real.len()];
                decode_frame_into(d, NatNetVersion::V3_0, &mut frame).expect("valid");
            }
        }
    });
    assert_eq!(info.count_total, 0, "{info:?}");
    assert!(
        client.poll_transmit().is_none(),
        "known markersets: no model def request"
    );
}
