//! Frame codec examples: sizes, both forms, and every typed rejection.

use protocol::{
    decode_frame_into, encode_frame_flat_into, encode_frame_into, frame_message_len, messages,
    DecodeError, EncodeError, FrameBuf, FrameForm, Limits,
};

fn face(n: usize) -> Vec<f32> {
    (0..n * 3).map(|i| i as f32 * 0.5 - 40.0).collect()
}

fn encoded(frame: &FrameBuf) -> Vec<u8> {
    let mut out = Vec::new();
    encode_frame_into(frame, &mut out).expect("finite positions");
    out
}

#[test]
fn a_109_marker_frame_is_1368_bytes_and_round_trips() {
    let mut f = FrameBuf::new();
    f.set_frame(42, 1_234_567_890_123, &face(109))
        .expect("valid");
    f.set_missing(0, true);
    f.set_missing(108, true);
    let bytes = encoded(&f);
    assert_eq!(bytes.len(), 1_368);
    assert_eq!(frame_message_len(109), 1_368);
    let mut g = FrameBuf::with_max_markers(109);
    let h = decode_frame_into(&bytes, &mut g).expect("valid frame");
    assert_eq!((h.frame_number, h.capture_time_us), (42, 1_234_567_890_123));
    assert_eq!(
        (h.marker_count, h.missing_count, h.form),
        (109, 2, FrameForm::Blob)
    );
    assert_eq!(g.missing_mask()[0], 1, "marker 0 is bit 0 of byte 0");
    assert_eq!(
        g.missing_mask()[13],
        1 << 4,
        "marker 108 is bit 4 of byte 13"
    );
    assert!(g.positions()[..3].iter().all(|v| v.is_nan()));
    assert_eq!(&g.positions()[3..324], &f.positions()[3..324]);
}

#[test]
fn the_flat_form_and_bundled_frames_decode_the_same() {
    let mut f = FrameBuf::new();
    let mut p = face(5);
    p[6..9].fill(f32::NAN);
    f.set_frame(-3, -9, &p).expect("valid");
    let mut flat = Vec::new();
    encode_frame_flat_into(&f, &mut flat).expect("finite");
    let mut g = FrameBuf::new();
    let h = decode_frame_into(&flat, &mut g).expect("flat frame");
    assert_eq!(
        (h.form, h.marker_count, h.missing_count),
        (FrameForm::Flat, 5, 1)
    );
    assert!(g.is_missing(2) && !g.is_missing(1));
    // the same frame, blob form, inside a bundle
    let blob = encoded(&f);
    let mut bundle = b"#bundle\0\0\0\0\0\0\0\0\x01".to_vec();
    bundle.extend_from_slice(&(blob.len() as u32).to_be_bytes());
    bundle.extend_from_slice(&blob);
    let msgs: Vec<_> = messages(&bundle, &Limits::default())
        .expect("valid")
        .collect();
    assert_eq!(msgs.len(), 1);
    let mut k = FrameBuf::new();
    decode_frame_into(msgs[0].bytes, &mut k).expect("bundled frame");
    assert_eq!(k.missing_mask(), g.missing_mask());
    assert_eq!(k.positions()[..6], g.positions()[..6]);
}

/// Overwrites the 4 bytes of coordinate `c` (0-based float index) of a `,ihbb` frame.
fn poke_coord(bytes: &mut [u8], markers: usize, c: usize, v: f32) {
    let at = frame_message_len(markers) - 12 * markers + 4 * c;
    bytes[at..at + 4].copy_from_slice(&v.to_be_bytes());
}

#[test]
fn bad_frames_get_typed_errors() {
    let mut f = FrameBuf::new();
    f.set_frame(1, 2, &face(3)).expect("valid");
    let good = encoded(&f);
    let mut g = FrameBuf::new();
    let dec = |b: &[u8], g: &mut FrameBuf| decode_frame_into(b, g).map(|h| h.marker_count);

    let mut nan = good.clone();
    poke_coord(&mut nan, 3, 4, f32::NAN);
    assert_eq!(dec(&nan, &mut g), Err(DecodeError::NonFinite { marker: 1 }));
    let mut inf = good.clone();
    poke_coord(&mut inf, 3, 8, f32::INFINITY);
    assert_eq!(dec(&inf, &mut g), Err(DecodeError::NonFinite { marker: 2 }));

    let mut trailing = good.clone();
    trailing.extend_from_slice(&[0; 4]);
    assert!(matches!(
        dec(&trailing, &mut g),
        Err(DecodeError::TrailingBytes { extra: 4, .. })
    ));
    assert!(matches!(
        dec(&good[..good.len() - 4], &mut g),
        Err(DecodeError::Truncated { .. })
    ));

    let mut tags = good.clone();
    tags[16..21].copy_from_slice(b",ihbf");
    assert_eq!(dec(&tags, &mut g), Err(DecodeError::WrongTypeTags));
    let mut addr = good.clone();
    addr[1] = b'n';
    assert_eq!(dec(&addr, &mut g), Err(DecodeError::UnknownAddress));

    // mask bit for a fourth marker that does not exist
    let mut mask = good.clone();
    mask[40] = 0b1000;
    assert_eq!(
        dec(&mask, &mut g),
        Err(DecodeError::WrongCount {
            expected: 3,
            got: 8
        })
    );

    let mut small = FrameBuf::with_max_markers(2);
    assert_eq!(
        dec(&good, &mut small),
        Err(DecodeError::TooManyMarkers { markers: 3, max: 2 })
    );

    let mut flat = Vec::new();
    let mut p = face(2);
    p[0] = f32::NAN;
    assert_eq!(
        f.set_frame(0, 0, &p),
        Err(DecodeError::PartlyMissing { marker: 0 })
    );
    f.set_frame(0, 0, &face(2)).expect("valid");
    encode_frame_flat_into(&f, &mut flat).expect("finite");
    let coords = flat.len() - 24;
    flat[coords..coords + 4].copy_from_slice(&f32::NAN.to_be_bytes());
    assert_eq!(
        dec(&flat, &mut g),
        Err(DecodeError::PartlyMissing { marker: 0 })
    );
    flat[coords..coords + 4].copy_from_slice(&f32::NEG_INFINITY.to_be_bytes());
    assert_eq!(
        dec(&flat, &mut g),
        Err(DecodeError::NonFinite { marker: 0 })
    );
}

#[test]
fn encoding_refuses_non_finite_present_markers_and_reuses_the_buffer() {
    let mut f = FrameBuf::new();
    f.set_frame(1, 2, &face(4)).expect("valid");
    f.positions_mut()[7] = f32::INFINITY;
    let mut out = Vec::with_capacity(2048);
    let cap = out.capacity();
    assert_eq!(
        encode_frame_into(&f, &mut out),
        Err(EncodeError::NonFinite { marker: 2 })
    );
    f.set_missing(2, true);
    assert_eq!(encode_frame_into(&f, &mut out), Ok(frame_message_len(4)));
    assert_eq!(out.capacity(), cap);
    // an edit that wrote into a missing marker does not leak onto the wire
    f.positions_mut()[6] = 5.0;
    encode_frame_into(&f, &mut out).expect("missing markers may hold anything");
    let mut g = FrameBuf::new();
    decode_frame_into(&out, &mut g).expect("valid");
    assert!(g.is_missing(2) && g.positions()[6..9].iter().all(|v| v.is_nan()));
    assert_eq!(g.positions()[..6], f.positions()[..6]);
    f.set_missing(2, false);
    f.positions_mut()[6..9].copy_from_slice(&[1.0, 2.0, 3.0]);
    assert_eq!(f.header().missing_count, 0);
    encode_frame_into(&f, &mut out).expect("finite again");
}

#[test]
fn a_109_marker_compact_bundle_fits_one_ethernet_payload() {
    let mut f = FrameBuf::new();
    f.set_frame(1, 2, &face(109)).expect("valid");
    let mut out = Vec::new();
    let tag = protocol::StreamTag {
        id: 1,
        name: "alice",
    };
    let n = protocol::encode_compact_into(&tag, &f, "neutral", 0.5, &mut out).expect("valid");
    assert_eq!(n, 1_464);
    let utc = protocol::FrameTime {
        timecode: None,
        irig: None,
        clock: protocol::CaptureClock::Utc,
    };
    protocol::append_timecode_element(&utc, &mut out);
    assert_eq!(
        out.len(),
        1_512,
        "with /mocap/timecode, as docs/osc.md says"
    );
    let long = "x".repeat(15);
    let n = protocol::encode_compact_into(&tag, &f, &long, 0.5, &mut out).expect("valid");
    assert_eq!(n, protocol::ETHERNET_PAYLOAD);
}
