//! The sans-IO client session against a scripted Motive stand-in: fake clock, bytes in memory.

use std::time::{Duration, Instant};

use crate::natnet_fixtures::fixture;
use protocol::natnet::*;

const HZ: u64 = 3_312_787;

fn info(app: &str, v: NatNetVersion) -> Vec<u8> {
    let mut out = Vec::new();
    let s = ServerInfo {
        app_name: app.into(),
        app_version: [2, 1, 0, 0],
        natnet_version: v,
        connection: Some(ConnectionInfo {
            clock_frequency_hz: HZ,
            data_port: 1511,
            multicast: true,
            multicast_group: DEFAULT_MULTICAST_GROUP,
        }),
    };
    encode_server_info_into(&s, &mut out).expect("encodable");
    out
}

/// Every queued transmit, decoded.
fn sent(c: &mut Client) -> Vec<Packet<'static>> {
    let mut out = Vec::new();
    while let Some(bytes) = c.poll_transmit() {
        let owned: &'static [u8] = Box::leak(bytes.to_vec().into_boxed_slice());
        out.push(decode_packet(owned).expect("client sends valid packets"));
    }
    out
}

fn events(c: &mut Client) -> Vec<Event> {
    std::iter::from_fn(|| c.poll_event()).collect()
}

fn frame_with(v: NatNetVersion, markerset: &str, params: u16) -> FrameOfData {
    let mut f = FrameOfData::default();
    f.push_markerset(markerset, &[[0.0; 3]]);
    f.params = FrameParams(params);
    let mut bytes = Vec::new();
    encode_frame_into(&f, v, &mut bytes).expect("encodable");
    f
}

/// A client connected to a Motive 2.1 stand-in with the real model defs, queues drained.
fn connected(t0: Instant) -> Client {
    let mut c = Client::new(ClientConfig::default(), t0);
    assert!(
        matches!(sent(&mut c)[..], [Packet::Connect(ref k)] if k.natnet_version == NatNetVersion::V3_0)
    );
    assert_eq!(
        c.handle_datagram(t0, Channel::Command, &info("Motive", NatNetVersion::V3_0)),
        Ok(Incoming::Handled)
    );
    assert!(matches!(events(&mut c)[..], [Event::Connected(ref s)] if s.app_name == "Motive"));
    assert_eq!(sent(&mut c), [Packet::RequestModelDef]);
    assert_eq!(c.frame_version(), Some(NatNetVersion::V3_0));
    c.handle_datagram(t0, Channel::Command, &fixture("modeldef_packet_v3.bin"))
        .expect("model defs");
    assert!(
        matches!(events(&mut c)[..], [Event::ModelDefs(ref d)] if d.markerset("all").is_some())
    );
    c
}

#[test]
fn connect_is_retried_until_the_server_answers() {
    let t0 = Instant::now();
    let mut c = Client::new(ClientConfig::default(), t0);
    assert_eq!(sent(&mut c).len(), 1);
    assert_eq!(c.poll_timeout(), Some(t0 + Duration::from_secs(1)));
    c.handle_timeout(t0 + Duration::from_millis(500));
    assert!(sent(&mut c).is_empty());
    c.handle_timeout(t0 + Duration::from_secs(1));
    assert!(matches!(sent(&mut c)[..], [Packet::Connect(_)]));
    // frames before the server info cannot be decoded yet
    let mut bytes = Vec::new();
    encode_frame_into(&FrameOfData::default(), NatNetVersion::V3_0, &mut bytes).expect("encodable");
    assert_eq!(
        c.handle_datagram(t0, Channel::Data, &bytes),
        Ok(Incoming::Ignored)
    );
    // an unsupported server is refused, and the client keeps trying
    let old = info("Motive", NatNetVersion::new(2, 10, 0, 0));
    assert!(matches!(
        c.handle_datagram(t0, Channel::Command, &old),
        Err(NatNetError::UnsupportedVersion {
            major: 2,
            minor: 10
        })
    ));
    assert!(c.server().is_none());
}

#[test]
fn keepalive_echo_and_clock_offset() {
    let t0 = Instant::now();
    let mut c = connected(t0);
    let t1 = t0 + Duration::from_millis(100);
    c.handle_timeout(t1);
    let out = sent(&mut c);
    assert_eq!(out[0], Packet::KeepAlive);
    let Packet::EchoRequest(stamp) = out[1] else {
        panic!("{out:?}")
    };
    assert_eq!(
        stamp, 100_000_000,
        "nanoseconds since the client's creation"
    );
    // the server's clock reads 500 s at the round trip's midpoint (1 ms each way)
    let mut reply = Vec::new();
    encode_echo_response_into(
        &EchoResponse {
            request_stamp: stamp,
            server_ticks: 500 * HZ,
        },
        &mut reply,
    );
    c.handle_datagram(t1 + Duration::from_millis(2), Channel::Command, &reply)
        .expect("echo");
    let [Event::ClockOffset(est)] = events(&mut c)[..] else {
        panic!()
    };
    assert_eq!(est.rtt, Duration::from_millis(2));
    assert!(
        (est.offset_s - (500.0 - 0.101)).abs() < 1e-9,
        "{}",
        est.offset_s
    );
    let at = c.server_ticks_to_instant(500 * HZ).expect("after creation");
    assert_eq!(at, t0 + Duration::from_millis(101));
    // a slower echo does not replace the better estimate
    c.handle_timeout(t1 + Duration::from_secs(1));
    let Packet::EchoRequest(s2) = sent(&mut c)[1] else {
        panic!()
    };
    encode_echo_response_into(
        &EchoResponse {
            request_stamp: s2,
            server_ticks: 501 * HZ,
        },
        &mut reply,
    );
    c.handle_datagram(t1 + Duration::from_millis(1_050), Channel::Command, &reply)
        .expect("echo");
    assert!(events(&mut c).is_empty());
}

#[test]
fn model_defs_are_requested_again_when_models_change() {
    let t0 = Instant::now();
    let mut c = connected(t0);
    let v = NatNetVersion::V3_0;
    c.handle_frame(t0, &frame_with(v, "all", 0));
    assert!(sent(&mut c).is_empty(), "known markerset");
    // within a second of the last request the change waits for the timer...
    c.handle_frame(t0, &frame_with(v, "all", 0x02));
    assert!(sent(&mut c).is_empty(), "rate-limited");
    assert_eq!(
        c.poll_timeout(),
        Some(t0 + Duration::from_secs(0)),
        "keep-alive due"
    );
    let t1 = t0 + Duration::from_secs(1);
    c.handle_frame(t1, &frame_with(v, "all", 0x02));
    assert_eq!(sent(&mut c), [Packet::RequestModelDef]);
    c.handle_frame(t1 + Duration::from_millis(8), &frame_with(v, "all", 0x02));
    assert!(sent(&mut c).is_empty(), "rate-limited");
    // no answer: the timer retries
    c.handle_timeout(t1 + Duration::from_secs(1));
    assert!(sent(&mut c).contains(&Packet::RequestModelDef));
    c.handle_datagram(t1, Channel::Command, &fixture("modeldef_packet_v3.bin"))
        .expect("defs");
    assert_eq!(events(&mut c).len(), 1);
    // a markerset the definitions do not describe
    c.handle_frame(t0 + Duration::from_secs(3), &frame_with(v, "face", 0));
    assert_eq!(sent(&mut c), [Packet::RequestModelDef]);
}

#[test]
fn silence_and_a_changed_server_reconnect() {
    let t0 = Instant::now();
    let mut c = connected(t0);
    c.handle_timeout(t0 + Duration::from_secs(3));
    assert_eq!(
        events(&mut c),
        [Event::Disconnected(DisconnectReason::Silent)]
    );
    assert!(sent(&mut c).iter().all(|p| matches!(p, Packet::Connect(_))));
    assert_eq!(c.frame_version(), None);

    let mut c = connected(t0);
    c.handle_datagram(t0, Channel::Command, &info("Motive", NatNetVersion::V3_0))
        .expect("same");
    assert!(
        events(&mut c).is_empty(),
        "the same server again changes nothing"
    );
    c.handle_datagram(t0, Channel::Command, &info("Motive", NatNetVersion::V4_1))
        .expect("changed");
    let ev = events(&mut c);
    assert_eq!(ev[0], Event::Disconnected(DisconnectReason::ServerChanged));
    assert!(matches!(ev[1], Event::Connected(ref s) if s.natnet_version == NatNetVersion::V4_1));
    assert_eq!(sent(&mut c), [Packet::RequestModelDef]);

    let mut bye = Vec::new();
    encode_empty_into(MessageId::Disconnect, &mut bye);
    c.handle_datagram(t0, Channel::Command, &bye)
        .expect("disconnect");
    assert_eq!(
        events(&mut c),
        [Event::Disconnected(DisconnectReason::ServerDisconnected)]
    );
}

#[test]
fn a_bitstream_reply_switches_the_frame_version() {
    let t0 = Instant::now();
    let mut c = connected(t0);
    let mut r = Vec::new();
    encode_text_into(MessageId::Response, "Bitstream,3.1", &mut r).expect("encodable");
    c.handle_datagram(t0, Channel::Command, &r)
        .expect("response");
    assert_eq!(events(&mut c), [Event::VersionChanged(NatNetVersion::V3_1)]);
    assert_eq!(c.frame_version(), Some(NatNetVersion::V3_1));
    // the real capture's command exchange leaves a connected client connected
    for d in crate::natnet_fixtures::traffic()
        .iter()
        .filter(|d| d.src_port == 1510)
    {
        c.handle_datagram(t0, Channel::Command, &d.payload)
            .expect("valid");
    }
}
