//! What a QTM client (the `--qtm` source) runs on QTM's bytes: the framer over a TCP stream cut
//! anywhere, then each packet's decoder (data frames, XML parameters, events). Never panics;
//! a decoded frame stays within its buffer and the labels within their bound.
#![no_main]

use libfuzzer_sys::fuzz_target;
use protocol::qtm::{
    decode_data_into, decode_packet, decode_parameters, FrameIn, Framer, PacketType,
    params_read::MAX_LABELS,
};

const MAX_MARKERS: usize = 64;

fuzz_target!(|data: &[u8]| {
    let mut frame = FrameIn::with_max_markers(MAX_MARKERS);
    if let Ok(p) = decode_packet(data) {
        if p.kind == PacketType::Data {
            let _ = decode_data_into(p.payload, &mut frame);
        }
    }
    let cut = data.first().map_or(1, |b| usize::from(*b).max(1));
    let mut framer = Framer::new(8192);
    for chunk in data.chunks(cut) {
        framer.buffer()[..chunk.len()].copy_from_slice(chunk);
        framer.filled(chunk.len());
        loop {
            let packet = match framer.next_packet() {
                Ok(Some(p)) => p,
                Ok(None) => break,
                Err(_) => return,
            };
            match packet.kind {
                PacketType::Data => {
                    if decode_data_into(packet.payload, &mut frame).is_ok() {
                        assert!(frame.marker_count() <= MAX_MARKERS);
                        assert_eq!(frame.positions().len(), 3 * frame.marker_count());
                    }
                }
                PacketType::Xml => {
                    if let Ok(text) = packet.text() {
                        if let Ok(p) = decode_parameters(text) {
                            assert!(p.labels.map_or(0, |l| l.len()) <= MAX_LABELS);
                        }
                    }
                }
                PacketType::Event => {
                    let _ = packet.event();
                }
                _ => {
                    let _ = packet.text();
                }
            }
        }
    }
});
