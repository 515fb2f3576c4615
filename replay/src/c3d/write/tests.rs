use super::*;

/// A file c3dio panics on (EVENT:USED past the header's 18 event slots makes it index the
/// header out of bounds) still reads, through the fallback decoder.
#[test]
fn a_panic_inside_c3dio_is_caught_and_the_fallback_reads_the_file() {
    let mut take = Take::new(vec!["a".into(), "b".into()], 50.0, 1);
    take.push_frame(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0], &[false, true]);
    let range = FrameRange::new(1, 1).expect("one frame");
    let meta = Meta {
        labels: &take.labels,
        rate_hz: take.rate_hz,
        time: None,
    };
    let mut params = parameters(&meta, &range, 3);
    // Append an EVENT group to the finished section: patch the last record's zero offset.
    let last = params.len() - 1 - 2; // the TRIAL:ACTUAL_END_FIELD offset word
    let mut w = Records {
        buf: std::mem::take(&mut params),
        pending: Some(last),
    };
    w.group(5, "EVENT", "");
    w.int(5, "USED", &[100]);
    let mut params = w.finish();
    params.resize(BLOCK, 0);
    params[2] = 1;
    let mut file = header(&meta, &range, 3).to_vec();
    file.extend_from_slice(&params);
    let mut frame = Vec::new();
    encode_frame(take.frame(0), take.frame_missing(0), &mut frame);
    file.extend_from_slice(&frame);
    file.resize(3 * BLOCK, 0);
    let (back, info) = crate::c3d::read_with_info(&file).expect("fallback reads it");
    assert_eq!(info.decoder, crate::c3d::Decoder::Fallback);
    assert_eq!(info.c3dio_error.as_deref(), Some("c3dio panicked"));
    assert_eq!(back.sample(0, 0), Some([1.0, 2.0, 3.0]));
    assert_eq!(back.sample(0, 1), None);
}
