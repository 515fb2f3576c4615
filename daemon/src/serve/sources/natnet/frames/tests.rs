use std::sync::Arc;

use protocol::natnet::{
    decode_model_defs, encode_frame_into, LabeledMarker, MarkerParams, MarkersetDef, RigidBodyDef,
};

use super::*;
use engine::pipeline::{Pipeline, PipelineConfig};
use engine::synthetic::random_model;
use engine::{Each, Processed};

/// A fixture of the real Motive 2.1 capture (protocol/tests/fixtures/natnet/SOURCE.txt).
fn fixture(name: &str) -> Vec<u8> {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../protocol/tests/fixtures/natnet")
        .join(name);
    std::fs::read(&p).unwrap_or_else(|e| panic!("fixture {} is missing: {e}", p.display()))
}

fn layout(defs: &ModelDefs, naming: &Naming) -> NatNetLayout {
    NatNetLayout::new(
        NatNetVersion::V3_0,
        3_312_787,
        None,
        defs,
        naming,
        &mut LayoutIds::default(),
    )
}

#[test]
fn the_real_capture_names_markers_as_motive_exports_them() {
    let defs =
        decode_model_defs(&fixture("modeldef_packet_v3.bin"), NatNetVersion::V3_0).expect("valid");
    let l = layout(&defs, &Naming::default());
    assert_eq!(l.markersets.len(), 1, "`all` is skipped");
    let quad = &l.markersets[0];
    assert_eq!((&*quad.name, quad.model_id), ("RaceQuad", Some(2)));
    assert_eq!(quad.labels[0], "RaceQuad:Marker1");
    let underscore = Naming {
        separator: Some("_".into()),
        rename: [("RaceQuad_Marker2".to_string(), "Nose".to_string())].into(),
    };
    let l = layout(&defs, &underscore);
    assert_eq!(&l.markersets[0].labels[..2], ["RaceQuad_Marker1", "Nose"]);
    let bare = Naming {
        separator: None,
        rename: HashMap::new(),
    };
    assert_eq!(layout(&defs, &bare).markersets[0].labels[4], "Marker5");
}

#[test]
fn positions_become_millimetres_and_occluded_markers_missing() {
    let defs = ModelDefs {
        markersets: vec![MarkersetDef {
            name: "FakeTree".into(),
            marker_names: (1..=5).map(|i| format!("M{i}")).collect(),
        }],
        rigid_bodies: vec![RigidBodyDef {
            name: "FakeTree".into(),
            id: 7,
            ..RigidBodyDef::default()
        }],
        ..ModelDefs::default()
    };
    let l = layout(&defs, &Naming::default());
    let mut frames = NatNetFrames::new(10);
    let mut out = FrameBuf::with_max_markers(10);
    // Marker 1 is not among the labelled markers, marker 2 is flagged occluded.
    frames
        .decode(&fixture("mocapframe_packet_occluded_v3.bin"), &l)
        .expect("valid");
    let header = frames
        .markerset_into(&l.markersets[0], &l, &mut out)
        .expect("the frame carries FakeTree");
    assert_eq!((header.frame_number, header.missing_count), (269_007, 2));
    assert!(out.is_missing(0) && out.is_missing(1) && !out.is_missing(2));
    let m = frames
        .frame()
        .markerset_named("FakeTree")
        .expect("sent")
        .positions[2];
    assert_eq!(&out.positions()[6..9], &m.map(|v| v * 1000.0));
    // Mid-exposure 8642283567331 ticks at 3,312,787 Hz.
    assert_eq!(header.capture_time_us, 2_608_765_238_251);
    assert_eq!(frames.time(&l).timecode, None, "Motive sent no timecode");
}

#[test]
fn without_labelled_markers_zero_positions_are_missing_and_timecode_comes_with_a_rate() {
    let defs = ModelDefs {
        markersets: vec![MarkersetDef {
            name: "Face".into(),
            marker_names: vec!["a".into(), "b".into()],
        }],
        ..ModelDefs::default()
    };
    let mut l = layout(&defs, &Naming::default());
    l.timecode_rate = Some(TimecodeRate::DF_29_97);
    let mut f = FrameOfData::default();
    f.frame_number = 5;
    f.push_markerset("Face", &[[0.0; 3], [0.5, 1.0, 1.5]]);
    f.timecode = 0x0A01_0002;
    f.timecode_subframe = 3;
    f.timestamp = 2.5;
    let mut bytes = Vec::new();
    encode_frame_into(&f, NatNetVersion::V3_0, &mut bytes).expect("encodable");
    let mut frames = NatNetFrames::new(4);
    frames.decode(&bytes, &l).expect("valid");
    let mut out = FrameBuf::with_max_markers(4);
    let h = frames
        .markerset_into(&l.markersets[0], &l, &mut out)
        .expect("carried");
    assert!(out.is_missing(0) && !out.is_missing(1));
    assert_eq!(&out.positions()[3..], &[500.0, 1000.0, 1500.0]);
    assert_eq!(
        h.capture_time_us, 2_500_000,
        "no mid-exposure: the timestamp"
    );
    let tc = frames.time(&l).timecode.expect("a timecode");
    assert_eq!(tc.to_string(), "10:01:00;02.3");
}

#[test]
fn each_markerset_is_a_stream_even_when_two_have_the_same_size() {
    let model = Arc::new(random_model(4, 2, 3));
    let names: Vec<String> = model.labels().to_vec();
    let defs = ModelDefs {
        markersets: ["Alice", "Bob", "all"]
            .iter()
            .map(|n| MarkersetDef {
                name: (*n).into(),
                marker_names: names.clone(),
            })
            .collect(),
        ..ModelDefs::default()
    };
    let bare = Naming {
        separator: None,
        rename: HashMap::new(),
    };
    let l = layout(&defs, &bare);
    let mut p = Pipeline::new(model, vec![], PipelineConfig::default());
    let server = "127.0.0.1:1510".parse().expect("addr");
    let mut f = FrameOfData::default();
    let mut frames = NatNetFrames::new(8);
    let mut buf = FrameBuf::with_max_markers(8);
    let mut seen = Vec::new();
    for n in 1..=3 {
        f.clear();
        f.frame_number = n;
        for who in ["Alice", "Bob", "all"] {
            let xyz: Vec<[f32; 3]> = (0..4).map(|i| [1.0 + i as f32 * 0.01, 1.0, 1.0]).collect();
            f.push_markerset(who, &xyz);
        }
        f.labeled_markers.push(LabeledMarker {
            id: 9 << 16 | 1,
            params: MarkerParams(1),
            ..LabeledMarker::default()
        });
        let mut bytes = Vec::new();
        encode_frame_into(&f, NatNetVersion::V3_0, &mut bytes).expect("encodable");
        frames
            .handle_datagram(server, &bytes, &l, &mut buf, &mut |frame| {
                let mut each = Each(|e: &Processed<'_>| {
                    let name = e.identity().name.clone();
                    seen.push((name, e.frame_number(), e.key.layout_id));
                });
                p.handle_frame(frame, &mut each);
            })
            .expect("decodes");
    }
    assert_eq!(seen.len(), 6, "{seen:?}");
    assert_eq!(seen[0], ("Alice".to_string(), 1, 0));
    assert_eq!(seen[1], ("Bob".to_string(), 1, 1));
    assert_eq!(p.stream_count(), 2);
    let bad = frames.handle_datagram(server, &[7, 0, 1, 0, 0], &l, &mut buf, &mut |_| {
        panic!("nothing decodes")
    });
    assert!(bad.is_err());
}

/// Motive with *Asset Markers* off (as in the real 2.1 capture) streams no markersets: the
/// asset's markers come from its labelled markers, occluded ones missing.
#[test]
fn without_asset_markers_the_labelled_markers_make_the_frame() {
    let defs =
        decode_model_defs(&fixture("modeldef_packet_v3.bin"), NatNetVersion::V3_0).expect("valid");
    let l = layout(&defs, &Naming::default());
    let mut f = FrameOfData::default();
    f.frame_number = 9;
    for (i, occluded) in [(1u32, false), (2, true), (4, false), (9, false)] {
        f.labeled_markers.push(LabeledMarker {
            id: 2 << 16 | i,
            position: [0.1 * i as f32, 1.0, -0.5],
            params: MarkerParams(u16::from(occluded)),
            ..LabeledMarker::default()
        });
    }
    let mut bytes = Vec::new();
    encode_frame_into(&f, NatNetVersion::V3_0, &mut bytes).expect("encodable");
    let mut frames = NatNetFrames::new(8);
    frames.decode(&bytes, &l).expect("valid");
    let mut out = FrameBuf::with_max_markers(8);
    let h = frames
        .markerset_into(&l.markersets[0], &l, &mut out)
        .expect("RaceQuad's labelled markers are there");
    assert_eq!(
        (h.marker_count, h.missing_count),
        (5, 3),
        "2 occluded, 3 and 5 absent"
    );
    assert_eq!(&out.positions()[..3], &[100.0, 1000.0, -500.0]);
    let x4 = 0.1 * 4.0_f32 * 1000.0;
    assert_eq!(&out.positions()[9..12], &[x4, 1000.0, -500.0]);
}
