//! decode_frame_into on arbitrary bytes: never panics, and whatever it accepts rosc reads the
//! same (frame number, time, positions of present markers).
#![no_main]

use libfuzzer_sys::fuzz_target;
use rosc::{OscPacket, OscType};
use protocol::{decode_frame_into, FrameBuf, FrameForm};

fuzz_target!(|data: &[u8]| {
    let mut buf = FrameBuf::with_max_markers(600);
    let Ok(h) = decode_frame_into(data, &mut buf) else {
        return;
    };
    let (rest, packet) = rosc::decoder::decode_udp(data).expect("rosc decodes an accepted frame");
    assert!(rest.is_empty());
    let OscPacket::Message(m) = packet else {
        panic!("accepted a bundle as a frame")
    };
    assert_eq!(m.args[0], OscType::Int(h.frame_number));
    assert_eq!(m.args[1], OscType::Long(h.capture_time_us));
    let floats: Vec<f32> = match h.form {
        FrameForm::Blob => {
            let OscType::Blob(pos) = &m.args[3] else {
                panic!("positions blob")
            };
            pos.chunks_exact(4)
                .map(|c| f32::from_be_bytes([c[0], c[1], c[2], c[3]]))
                .collect()
        }
        FrameForm::Flat => m.args[2..]
            .iter()
            .map(|a| a.clone().float().expect("float"))
            .collect(),
    };
    assert_eq!(floats.len(), buf.positions().len());
    for (i, (a, b)) in floats.iter().zip(buf.positions()).enumerate() {
        if buf.is_missing(i / 3) {
            assert!(b.is_nan());
        } else {
            assert!(a.is_finite() && a.to_bits() == b.to_bits());
        }
    }
});
