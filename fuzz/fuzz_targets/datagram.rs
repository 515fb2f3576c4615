//! The pre-scan and message walk on arbitrary datagrams: never panics, never recurses past the
//! limit, and whatever it passes rosc decodes whole (rosc is only called after the pre-scan,
//! as in the daemon, since rosc itself overflows the stack on deep bundles).
#![no_main]

use libfuzzer_sys::fuzz_target;

use protocol::{decode_frame_into, messages, Address, FrameBuf, Limits};

fuzz_target!(|data: &[u8]| {
    let Ok(msgs) = messages(data, &Limits::default()) else {
        return;
    };
    let mut buf = FrameBuf::with_max_markers(600);
    let mut total = 0;
    for m in msgs {
        assert_eq!(m.bytes.len() % 4, 0);
        total += m.bytes.len();
        match Address::parse(m.address) {
            Some(Address::Frame) => drop(decode_frame_into(m.bytes, &mut buf)),
            Some(Address::Timecode) => drop(protocol::decode_timecode(m.bytes)),
            _ => drop(protocol::decode_control(m.bytes)),
        }
    }
    assert!(total <= data.len());
    let (rest, _) = rosc::decoder::decode_udp(data).expect("rosc decodes a pre-scanned datagram");
    assert!(rest.is_empty());
});
