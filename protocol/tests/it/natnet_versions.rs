//! Version-specific layouts the round trips cannot reach: NatNet 4.1 section sizes checked,
//! assets skipped, unknown descriptions skipped by size, 4.0's optional precision timestamp.

use protocol::natnet::*;

fn empty_frame(v: NatNetVersion) -> Vec<u8> {
    let mut out = Vec::new();
    encode_frame_into(&FrameOfData::default(), v, &mut out).expect("encodable");
    out
}

fn fix_header(p: &mut [u8]) {
    let n = (p.len() - HEADER_LEN) as u16;
    p[2..4].copy_from_slice(&n.to_le_bytes());
}

#[test]
fn a_wrong_4_1_section_size_is_rejected() {
    let mut p = empty_frame(NatNetVersion::V4_1);
    // header, frame number, markerset count, then the markerset section size
    p[12..16].copy_from_slice(&4i32.to_le_bytes());
    let mut f = FrameOfData::default();
    assert_eq!(
        decode_frame_into(&p, NatNetVersion::V4_1, &mut f),
        Err(NatNetError::SectionSize {
            offset: 12,
            declared: 4,
            actual: 0
        })
    );
    // the same bytes read as 4.0 have no sizes: misread, and rejected, not misdecoded
    assert!(decode_frame_into(&p, NatNetVersion::V4_0, &mut f).is_err());
}

#[test]
fn a_4_1_asset_is_skipped() {
    let mut p = empty_frame(NatNetVersion::V4_1);
    // empty 4.1 frame: header 4, number 4, four sections (count, size) 32, then the assets
    let at = 4 + 4 + 4 * 8;
    assert_eq!(&p[at..at + 8], &[0; 8]);
    let mut asset = Vec::new();
    asset.extend_from_slice(&9i32.to_le_bytes()); // asset id
    asset.extend_from_slice(&1i32.to_le_bytes()); // one rigid body: id, pose, error, params
    asset.extend_from_slice(&[0; 4 + 12 + 16 + 4 + 2]);
    asset.extend_from_slice(&1i32.to_le_bytes()); // one marker: id, pos, size, params, residual
    asset.extend_from_slice(&[0; 4 + 12 + 4 + 2 + 4]);
    let mut section = 1i32.to_le_bytes().to_vec();
    section.extend_from_slice(&(asset.len() as i32).to_le_bytes());
    section.extend_from_slice(&asset);
    p.splice(at..at + 8, section);
    fix_header(&mut p);
    let mut f = FrameOfData::default();
    decode_frame_into(&p, NatNetVersion::V4_1, &mut f).expect("valid");
    assert_eq!(f.asset_count, 1);
}

#[test]
fn a_4_1_description_of_unknown_type_is_skipped_by_its_size() {
    let defs = ModelDefs {
        markersets: vec![MarkersetDef {
            name: "face".into(),
            marker_names: vec!["a".into()],
        }],
        ..ModelDefs::default()
    };
    let mut p = Vec::new();
    encode_model_defs_into(&defs, NatNetVersion::V4_1, &mut p).expect("encodable");
    p[4..8].copy_from_slice(&2i32.to_le_bytes());
    p.extend_from_slice(&99i32.to_le_bytes());
    p.extend_from_slice(&3i32.to_le_bytes());
    p.extend_from_slice(b"xyz");
    fix_header(&mut p);
    let back = decode_model_defs(&p, NatNetVersion::V4_1).expect("skips type 99");
    assert_eq!(
        (back.markersets, back.skipped_types),
        (defs.markersets, vec![99])
    );
    // before 4.1 nothing says how long it is
    let mut q = Vec::new();
    encode_model_defs_into(&ModelDefs::default(), NatNetVersion::V3_0, &mut q).expect("encodable");
    q[4..8].copy_from_slice(&1i32.to_le_bytes());
    q.extend_from_slice(&99i32.to_le_bytes());
    fix_header(&mut q);
    assert_eq!(
        decode_model_defs(&q, NatNetVersion::V3_0),
        Err(ModelDefError::Description {
            index: 0,
            type_id: 99,
            source: NatNetError::UnknownDescription {
                type_id: 99,
                offset: 8
            }
        })
    );
}

#[test]
fn a_4_0_frame_decodes_with_or_without_the_precision_timestamp() {
    let mut f = FrameOfData::default();
    for precision in [
        None,
        Some(PrecisionTimestamp {
            seconds: 5,
            fraction: 7,
        }),
    ] {
        f.precision_timestamp = precision;
        let mut p = Vec::new();
        encode_frame_into(&f, NatNetVersion::V4_0, &mut p).expect("encodable");
        let mut back = FrameOfData::default();
        decode_frame_into(&p, NatNetVersion::V4_0, &mut back).expect("valid");
        assert_eq!(back.precision_timestamp, precision);
    }
}

#[test]
fn infinities_are_rejected_and_nan_passes() {
    let mut f = FrameOfData::default();
    f.other_markers = vec![[f32::NAN, 0.0, 0.0]];
    let mut p = Vec::new();
    encode_frame_into(&f, NatNetVersion::V3_0, &mut p).expect("encodable");
    let mut back = FrameOfData::default();
    decode_frame_into(&p, NatNetVersion::V3_0, &mut back).expect("NaN is 'no value'");
    assert!(back.other_markers[0][0].is_nan());
    f.other_markers = vec![[f32::INFINITY, 0.0, 0.0]];
    encode_frame_into(&f, NatNetVersion::V3_0, &mut p).expect("encodable");
    assert_eq!(
        decode_frame_into(&p, NatNetVersion::V3_0, &mut back).map_err(NatNetError::kind),
        Err(NatNetErrorKind::NonFinite)
    );
    f.other_markers.clear();
    f.timestamp = f64::NAN;
    encode_frame_into(&f, NatNetVersion::V3_0, &mut p).expect("encodable");
    assert_eq!(
        decode_frame_into(&p, NatNetVersion::V3_0, &mut back).map_err(NatNetError::kind),
        Err(NatNetErrorKind::NonFinite)
    );
}
