use super::*;

#[test]
fn timecode_prints_like_sampleclient() {
    let t = Timecode::from_packed(0x0102_0304, 7);
    assert_eq!(t.to_string(), "01:02:03:04.7");
    assert_eq!(Timecode::from_packed(0, 0).to_string(), "00:00:00:00.0");
}

#[test]
fn spans_and_helpers() {
    let mut f = FrameOfData::default();
    f.push_markerset("a", &[[1.0, 2.0, 3.0]]);
    f.push_markerset("bb", &[]);
    f.devices.push(3, &[&[1.0, 2.0], &[]]);
    assert_eq!(f.markerset(0).map(|m| m.positions.len()), Some(1));
    assert_eq!(f.markerset_named("bb").map(|m| m.name), Some("bb"));
    assert_eq!(f.devices.samples(0, 0), Some(&[1.0f32, 2.0][..]));
    assert_eq!(f.devices.channel_count(0), 2);
    let mut mm = Vec::new();
    positions_mm_into(f.markerset(0).expect("one").positions, &mut mm);
    assert_eq!(mm, [1000.0, 2000.0, 3000.0]);
    let m = LabeledMarker {
        id: 2 << 16 | 5,
        ..LabeledMarker::default()
    };
    assert_eq!((m.model_id(), m.marker_index()), (2, 5));
}
