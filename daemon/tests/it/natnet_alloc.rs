//! Issue 16: the NatNet input path allocates nothing once warm. 10,000 NatNet frames (two
//! 109-marker markersets, one performer each, labelled markers telling occlusion, timecode)
//! as the NatNet source decodes them into source frames (`NatNetFrames::handle_datagram`),
//! through `Pipeline::handle_frame`, every output profile encoded with the timecode, counted
//! by allocation-counter's global allocator.

use std::net::SocketAddr;
use std::sync::Arc;

use daemon::loopback::synthetic::{frame_into, random_model};
use daemon::serve::sinks::osc::encode::EncodeOnly;
use daemon::serve::sources::natnet::frames::{LayoutIds, Naming, NatNetFrames, NatNetLayout};
use engine::pipeline::{Pipeline, PipelineConfig};
use engine::{Each, Processed, Sink};
use protocol::natnet::{
    encode_frame_into, FrameOfData, LabeledMarker, MarkerParams, MarkersetDef, ModelDefs,
    NatNetVersion, RigidBodyDef,
};
use protocol::{FrameBuf, TimecodeRate};

const MARKERS: usize = 109;

#[test]
fn the_natnet_frame_path_does_not_allocate() {
    let model = Arc::new(random_model(MARKERS, 20, 4));
    let mut p = Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default());
    let sets = ["Alice", "Bob"];
    let defs = ModelDefs {
        markersets: sets
            .iter()
            .map(|n| MarkersetDef {
                name: (*n).into(),
                marker_names: model.labels().to_vec(),
            })
            .collect(),
        rigid_bodies: vec![RigidBodyDef {
            name: "Alice".into(),
            id: 3,
            ..RigidBodyDef::default()
        }],
        ..ModelDefs::default()
    };
    let naming = Naming {
        separator: None,
        ..Naming::default()
    };
    let layout = NatNetLayout::new(
        NatNetVersion::V4_1,
        1_000_000,
        Some(TimecodeRate::DF_29_97),
        &defs,
        &naming,
        &mut LayoutIds::default(),
    );
    let server: SocketAddr = "127.0.0.1:1510".parse().expect("literal");
    let mut xyz = vec![0.0f32; MARKERS * 3];
    let mut frame = FrameOfData::default();
    let datagrams: Vec<Vec<u8>> = (0..16)
        .map(|f| {
            frame_into(&model, f, &mut xyz);
            frame.clear();
            for name in sets {
                let m: Vec<[f32; 3]> = xyz
                    .chunks_exact(3)
                    .map(|c| [c[0] / 1e3, c[1] / 1e3, c[2] / 1e3])
                    .collect();
                frame.push_markerset(name, &m);
            }
            for i in 1..=MARKERS as u32 {
                frame.labeled_markers.push(LabeledMarker {
                    id: 3 << 16 | i,
                    params: MarkerParams(u16::from(f % 4 == 0 && i < 4)),
                    ..LabeledMarker::default()
                });
            }
            frame.timecode = 0x0A00_0000 | f as u32;
            frame.camera_mid_exposure = 1_000 + f as u64;
            let mut d = Vec::new();
            encode_frame_into(&frame, NatNetVersion::V4_1, &mut d).expect("encodes");
            d
        })
        .collect();
    let mut datagrams = datagrams;
    let mut frames = NatNetFrames::new(1_000);
    let mut buf = FrameBuf::with_max_markers(1_000);
    let mut encoded = EncodeOnly::all(1_000);
    let mut timed = 0u64;
    let mut run = |p: &mut Pipeline, from: i32, count: i32| {
        for n in from..from + count {
            let d = &mut datagrams[n as usize % 16];
            // frame number right after the 4-byte header
            d[4..8].copy_from_slice(&n.to_le_bytes());
            frames
                .handle_datagram(server, d, &layout, &mut buf, &mut |f| {
                    p.handle_frame(
                        f,
                        &mut Each(|e: &Processed<'_>| {
                            encoded.handle_frame(e);
                            timed += u64::from(e.time.timecode.is_some());
                        }),
                    );
                })
                .expect("decodes");
        }
    };
    run(&mut p, 0, 200);
    let info = allocation_counter::measure(|| run(&mut p, 200, 10_000));
    assert_eq!(
        p.counters.frames_out,
        2 * 10_200,
        "every markerset processed"
    );
    assert!(
        p.counters.missing_markers > 0,
        "occluded markers were missing"
    );
    assert!(encoded.bytes > 2 * 10_200 * 1_000, "every profile encoded");
    assert_eq!(timed, 2 * 10_200, "every frame with its timecode");
    assert_eq!(
        info.count_total, 0,
        "allocations in 10,000 frames: {info:?}"
    );
}
