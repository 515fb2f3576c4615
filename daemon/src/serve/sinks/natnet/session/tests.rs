use std::net::{Ipv4Addr, SocketAddr};

use protocol::natnet::{
    decode_packet, encode_connect_into, encode_echo_request_into, encode_empty_into,
    encode_request_into, response_text, Connect, MessageId, NatNetVersion, Packet,
};

use super::super::counters::REPLY_BURST_BYTES;
use super::*;

fn session(multicast: Option<SocketAddrV4>) -> Session {
    let identity = Identity {
        app_version: [0, 1, 0, 0],
        data_port: 1511,
        multicast,
        version: NatNetVersion::V4_1,
    };
    Session::new(identity, AllowList::loopback(), 2)
}

fn peer(port: u16) -> SocketAddr {
    (Ipv4Addr::LOCALHOST, port).into()
}

/// Sends `datagram` from `from` at `now`; the reply, if any.
fn ask(s: &mut Session, now: Instant, from: SocketAddr, datagram: &[u8]) -> Option<Vec<u8>> {
    let mut out = Vec::new();
    s.handle_command(now, 42, (from, datagram), &mut out)
        .then_some(out)
}

fn empty(id: MessageId) -> Vec<u8> {
    let mut out = Vec::new();
    encode_empty_into(id, &mut out);
    out
}

fn connect(version: NatNetVersion) -> Vec<u8> {
    let mut out = Vec::new();
    encode_connect_into(&Connect::emoshift(version), false, &mut out)
        .expect("the test's own values are valid");
    out
}

#[test]
fn a_connect_is_answered_and_frames_flow_after_a_keep_alive() {
    let mut s = session(None);
    let t0 = Instant::now();
    let reply = ask(&mut s, t0, peer(5000), b"\x00\x00\x05\x00Ping\0").expect("server info");
    let Ok(Packet::ServerInfo(info)) = decode_packet(&reply) else {
        panic!("server info, got {reply:?}");
    };
    assert_eq!(info.app_name, "emoshift");
    assert_eq!(info.natnet_version, NatNetVersion::V4_1);
    let c = info.connection.expect("connection info");
    assert_eq!(
        (c.data_port, c.multicast, c.clock_frequency_hz),
        (1511, false, CLOCK_HZ)
    );
    // Answered, but no frames to an address that has not kept a session alive.
    assert_eq!(s.client_count(), 0);
    assert_eq!(s.pending(), 1);
    assert!(ask(&mut s, t0, peer(5000), &empty(MessageId::KeepAlive)).is_none());
    assert_eq!(s.client_count(), 1);
    assert_eq!(s.client(0).map(|c| c.wants), Some(NatNetVersion::V4_1));
    // A keep-alive from a stranger is not a session.
    ask(&mut s, t0, peer(5001), &empty(MessageId::KeepAlive));
    assert_eq!(s.client_count(), 1);
    assert_eq!(s.counters.keepalives_unknown, 1);
    // The lease ends without keep-alives.
    s.poll_expired(t0 + LEASE + Duration::from_millis(1));
    assert_eq!(s.client_count(), 0);
    assert_eq!(s.counters.expired, 1);
}

#[test]
fn each_unicast_client_has_its_bitstream() {
    let mut s = session(None);
    let t0 = Instant::now();
    let reply = ask(&mut s, t0, peer(1), &connect(NatNetVersion::V3_0))
        .expect("the test's own values are valid");
    let Ok(Packet::ServerInfo(info)) = decode_packet(&reply) else {
        panic!("server info");
    };
    assert_eq!(info.natnet_version, NatNetVersion::V3_1);
    ask(&mut s, t0, peer(1), &empty(MessageId::KeepAlive));
    ask(&mut s, t0, peer(2), &connect(NatNetVersion::V4_1));
    ask(&mut s, t0, peer(2), &empty(MessageId::KeepAlive));
    let mut req = Vec::new();
    encode_request_into("Bitstream,3.1", &mut req).expect("the test's own values are valid");
    let reply = ask(&mut s, t0, peer(2), &req).expect("the test's own values are valid");
    let Ok(Packet::Response(p)) = decode_packet(&reply) else {
        panic!("a response");
    };
    assert_eq!(response_text(p), Some("Bitstream,3.1"));
    encode_request_into("Bitstream,2.9", &mut req).expect("the test's own values are valid");
    let reply = ask(&mut s, t0, peer(1), &req).expect("the test's own values are valid");
    assert_eq!(decode_packet(&reply), Ok(Packet::Response(&[1, 0, 0, 0])));
    let versions: Vec<_> = s.clients().map(|c| (c.addr, c.wants)).collect();
    assert_eq!(
        versions,
        [
            (peer(1), NatNetVersion::V3_1),
            (peer(2), NatNetVersion::V3_1)
        ]
    );
    // The table is bounded: a third client waits, counted.
    ask(&mut s, t0, peer(3), &connect(NatNetVersion::V4_1));
    ask(&mut s, t0, peer(3), &empty(MessageId::KeepAlive));
    assert_eq!(s.client_count(), 2);
    assert_eq!(s.counters.clients_full, 1);
    ask(&mut s, t0, peer(1), &empty(MessageId::Disconnect));
    ask(&mut s, t0, peer(3), &empty(MessageId::KeepAlive));
    assert_eq!(s.client_count(), 2);
}

#[test]
fn requests_are_answered_as_motive_answers_them() {
    let mut s = session(None);
    s.rate_hz = 120.0;
    let t0 = Instant::now();
    let mut req = Vec::new();
    for (text, want) in [
        ("FrameRate", 120.0f32.to_le_bytes()),
        ("UnitsToMillimeters", 1000.0f32.to_le_bytes()),
        ("TimelinePlay", [0; 4]),
        ("TimelineStop", [0; 4]),
    ] {
        encode_request_into(text, &mut req).expect("the test's own values are valid");
        let reply = ask(&mut s, t0, peer(1), &req).expect("the test's own values are valid");
        assert_eq!(
            decode_packet(&reply),
            Ok(Packet::Response(&want[..])),
            "{text}"
        );
    }
    for unknown in [
        {
            encode_request_into("SetPlaybackCurrentFrame,0", &mut req)
                .expect("the test's own values are valid");
            req.clone()
        },
        vec![77, 0, 0, 0],
    ] {
        let reply = ask(&mut s, t0, peer(1), &unknown).expect("an error response");
        assert_eq!(decode_packet(&reply), Ok(Packet::UnrecognizedRequest));
    }
    let mut echo = Vec::new();
    encode_echo_request_into(9, &mut echo);
    let reply = ask(&mut s, t0, peer(1), &echo).expect("the test's own values are valid");
    let Ok(Packet::EchoResponse(e)) = decode_packet(&reply) else {
        panic!("echo");
    };
    assert_eq!((e.request_stamp, e.server_ticks), (9, 42));
    let reply = ask(&mut s, t0, peer(1), &empty(MessageId::RequestModelDef))
        .expect("the test's own values are valid");
    assert_eq!(decode_packet(&reply), Ok(Packet::ModelDef));
}

#[test]
fn bad_input_is_counted_and_never_amplified() {
    let mut s = session(None);
    let t0 = Instant::now();
    let stranger: SocketAddr = (Ipv4Addr::new(10, 0, 0, 9), 1510).into();
    assert!(ask(&mut s, t0, stranger, &connect(NatNetVersion::V4_1)).is_none());
    assert!(ask(&mut s, t0, peer(1), &vec![0; MAX_COMMAND_LEN + 1]).is_none());
    assert!(ask(&mut s, t0, peer(1), &[0, 0, 200, 0]).is_none());
    assert!(ask(&mut s, t0, peer(1), &[1, 0, 0, 0]).is_none());
    let c = &s.counters;
    assert_eq!(
        (c.not_allowed, c.oversized, c.malformed, c.not_commands),
        (1, 1, 1, 1)
    );
    // A flood of 4-byte requests for model definitions: replies stop at the budget.
    s.defs.markersets.push(protocol::natnet::MarkersetDef {
        name: "Face".into(),
        marker_names: (0..109).map(|i| format!("marker{i}")).collect(),
    });
    let ask_defs = empty(MessageId::RequestModelDef);
    let mut replied = 0usize;
    for _ in 0..10_000 {
        replied += ask(&mut s, t0, peer(1), &ask_defs).map_or(0, |r| r.len());
    }
    assert!(replied <= REPLY_BURST_BYTES as usize, "{replied} bytes");
    assert!(s.counters.over_budget > 9_000);
    // The budget comes back with time.
    assert!(ask(&mut s, t0 + Duration::from_secs(1), peer(1), &ask_defs).is_some());
}

#[test]
fn multicast_answers_with_the_group_and_keeps_no_table() {
    let group: SocketAddrV4 = "239.255.42.99:1511"
        .parse()
        .expect("the test's own values are valid");
    let mut s = session(Some(group));
    let t0 = Instant::now();
    let reply = ask(&mut s, t0, peer(1), &connect(NatNetVersion::V3_0))
        .expect("the test's own values are valid");
    let Ok(Packet::ServerInfo(info)) = decode_packet(&reply) else {
        panic!("server info");
    };
    let c = info.connection.expect("the test's own values are valid");
    assert_eq!(
        (c.multicast, c.multicast_group, c.data_port),
        (true, [239, 255, 42, 99], 1511)
    );
    assert_eq!(info.natnet_version, NatNetVersion::V4_1);
    assert_eq!((s.pending(), s.client_count()), (0, 0));
    assert_eq!(s.multicast(), Some((group, NatNetVersion::V4_1)));
    let mut req = Vec::new();
    encode_request_into("Bitstream,3.1", &mut req).expect("the test's own values are valid");
    ask(&mut s, t0, peer(1), &req);
    assert_eq!(s.multicast(), Some((group, NatNetVersion::V3_1)));
}
