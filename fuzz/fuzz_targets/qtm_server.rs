//! What the QTM server (`--qtm-server`) runs on a client's bytes: the framer over a TCP stream
//! cut anywhere (a packet over its limit is an error, never a panic or a large allocation),
//! each command text parsed, and discovery requests. A parsed `StreamFrames` or
//! `GetCurrentFrame` encodes a frame with its components that decodes again.
#![no_main]

use libfuzzer_sys::fuzz_target;
use protocol::qtm::{
    decode_data_into, decode_discover, decode_packet, encode_data_into, parse_command, Command,
    DataFrame, FrameIn, Framer, HEADER_BYTES,
};

fuzz_target!(|data: &[u8]| {
    let _ = decode_discover(data);
    let cut = data.first().map_or(1, |b| usize::from(*b).max(1));
    let mut framer = Framer::new(1024);
    let mut out = Vec::new();
    for chunk in data.chunks(cut) {
        framer.buffer()[..chunk.len()].copy_from_slice(chunk);
        framer.filled(chunk.len());
        loop {
            let packet = match framer.next_packet() {
                Ok(Some(p)) => p,
                Ok(None) => break,
                Err(_) => return,
            };
            assert!(packet.payload.len() + HEADER_BYTES <= 1024);
            let Ok(text) = packet.text() else { continue };
            let components = match parse_command(text) {
                Command::StreamFrames { components: Ok(c), .. } => c,
                Command::GetCurrentFrame(Ok(c)) => c,
                _ => continue,
            };
            let frame = DataFrame {
                timestamp_us: 1,
                frame_number: 2,
                positions: &[1.0, 2.0, 3.0, f32::NAN, f32::NAN, f32::NAN],
                timecode: None,
            };
            encode_data_into(&frame, components, &mut out);
            let p = decode_packet(&out).expect("an encoded frame is one whole packet");
            let mut back = FrameIn::with_max_markers(2);
            decode_data_into(p.payload, &mut back).expect("an encoded frame decodes");
            assert_eq!(back.frame_number, 2);
        }
    }
});
