//! Every NatNet decoder on arbitrary datagrams, at every supported version: never panics, and
//! whatever decodes re-encodes to bytes that decode and re-encode to the same bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;
use protocol::natnet::{
    decode_frame_into, decode_model_defs, decode_packet, encode_frame_into,
    encode_model_defs_into, FrameOfData, NatNetVersion,
};

const VERSIONS: [NatNetVersion; 4] = [
    NatNetVersion::V3_0,
    NatNetVersion::V4_0,
    NatNetVersion::V4_1,
    NatNetVersion::new(2, 9, 0, 0),
];

fuzz_target!(|data: &[u8]| {
    let _ = decode_packet(data);
    let mut frame = FrameOfData::default();
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for v in VERSIONS {
        if decode_frame_into(data, v, &mut frame).is_ok() {
            encode_frame_into(&frame, v, &mut a).expect("a decoded frame encodes");
            decode_frame_into(&a, v, &mut frame).expect("an encoded frame decodes");
            encode_frame_into(&frame, v, &mut b).expect("a decoded frame encodes");
            assert_eq!(a, b);
        }
        if let Ok(defs) = decode_model_defs(data, v) {
            encode_model_defs_into(&defs, v, &mut a).expect("decoded defs encode");
            let again = decode_model_defs(&a, v).expect("encoded defs decode");
            encode_model_defs_into(&again, v, &mut b).expect("decoded defs encode");
            assert_eq!(a, b);
        }
    }
});
