use std::io::Write;
use std::sync::{Arc, Mutex};

use protocol::qtm::{decode_packet, Event, PacketType};

use super::*;

/// A writer that keeps what it is given (or takes nothing: a client that never reads).
#[derive(Clone, Default)]
struct Wire {
    bytes: Arc<Mutex<Vec<u8>>>,
    full: bool,
}

impl Write for Wire {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        if self.full {
            return Err(std::io::ErrorKind::WouldBlock.into());
        }
        self.bytes.lock().expect("test lock").extend_from_slice(b);
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Wire {
    /// Every packet received, as (type, payload).
    fn packets(&self) -> Vec<(PacketType, Vec<u8>)> {
        let bytes = self.bytes.lock().expect("test lock");
        let mut out = Vec::new();
        let mut at = 0;
        while at + 8 <= bytes.len() {
            let size = u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4")) as usize;
            let p = decode_packet(&bytes[at..at + size]).expect("whole packet");
            out.push((p.kind, p.payload.to_vec()));
            at += size;
        }
        out
    }
}

fn hub_with_client(wire: &Wire) -> Hub {
    let mut hub = Hub::default();
    let peer = "127.0.0.1:5000".parse().expect("addr");
    assert_eq!(
        hub.add(1, peer, Outbox::new(Box::new(wire.clone()))),
        After::Continue
    );
    hub
}

fn text(p: &(PacketType, Vec<u8>)) -> String {
    String::from_utf8_lossy(p.1.strip_suffix(&[0]).unwrap_or(&p.1)).into_owned()
}

#[test]
fn answers_as_qtm_does() {
    let wire = Wire::default();
    let mut hub = hub_with_client(&wire);
    for c in [
        "Version 1.25",
        "Version",
        "ByteOrder",
        "QTMVersion",
        "GetState",
        "GetParameters All",
        "GetCurrentFrame 3D",
        "TakeControl pw",
        "GetParameters 6D",
        "StreamFrames AllFrames UDP:9 6D",
        "StreamFrames AllFrames UDP:127.0.0.9:4545 3D",
        "bogus",
        "Version 2.0",
    ] {
        assert_eq!(hub.handle_command(1, c), After::Continue, "{c}");
    }
    let got = wire.packets();
    assert_eq!(text(&got[0]), "QTM RT Interface connected");
    assert_eq!(text(&got[1]), "Version set to 1.25");
    assert_eq!(text(&got[2]), "Version is 1.25");
    assert_eq!(text(&got[3]), "Byte order is little endian");
    assert!(text(&got[4]).starts_with("QTM Version is emoshift"));
    assert_eq!(
        got[5],
        (PacketType::Event, vec![Event::ConnectionClosed.as_u8()])
    );
    assert_eq!(got[6].0, PacketType::Xml);
    assert!(text(&got[6]).contains("<Labels>0</Labels>"));
    assert_eq!(got[7].0, PacketType::NoMoreData);
    for p in &got[8..] {
        assert_eq!(p.0, PacketType::Error, "{}", text(p));
    }
    assert_eq!(got.len(), 14);
    assert_eq!(hub.counters.refused_commands, 6);
    assert_eq!(hub.handle_command(1, "Disconnect"), After::Close);
}

#[test]
fn streams_at_the_asked_rate_and_to_the_clients_own_address() {
    let wire = Wire::default();
    let mut hub = hub_with_client(&wire);
    hub.handle_command(1, "StreamFrames FrequencyDivisor:3 UDP:4545 3D");
    let s = hub.clients[0].stream.expect("streaming");
    assert_eq!(s.udp, Some("127.0.0.1:4545".parse().expect("addr")));
    let mut s = s;
    let due: Vec<bool> = (0..6).map(|_| s.due(120.0)).collect();
    assert_eq!(due, [true, false, false, true, false, false]);
    hub.handle_command(1, "StreamFrames Frequency:30 3D");
    let mut s = hub.clients[0].stream.expect("streaming");
    let sent = (0..120).filter(|_| s.due(120.0)).count();
    assert_eq!(sent, 30);
    hub.handle_command(1, "StreamFrames Stop");
    assert!(hub.clients[0].stream.is_none());
}

#[test]
fn a_client_that_never_reads_loses_frames_then_is_dropped_on_replies() {
    let wire = Wire {
        full: true,
        ..Wire::default()
    };
    let mut hub = Hub::default();
    let peer = "127.0.0.1:5000".parse().expect("addr");
    hub.add(1, peer, Outbox::new(Box::new(wire)));
    let frame = vec![0u8; 1000];
    assert_eq!(
        hub.clients[0].outbox.send_frame(&frame),
        Err(Refused::Behind)
    );
    let mut dead = false;
    for _ in 0..(outbox::MAX_PENDING / 1000 + 2) {
        if hub.clients[0].outbox.send_reply(&frame) == Err(Refused::Dead) {
            dead = true;
            break;
        }
    }
    assert!(dead, "a reply queue is bounded");
    hub.parameters_changed();
    assert!(
        hub.clients.is_empty(),
        "the client that owes too much is dropped"
    );
}
