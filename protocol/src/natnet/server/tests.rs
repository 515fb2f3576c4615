use super::*;
use crate::natnet::{
    decode_packet, encode_connect_into, encode_echo_request_into, encode_empty_into,
    encode_request_into, Connect, Packet,
};

#[test]
fn connects_of_every_client_kind_decode() {
    let mut out = Vec::new();
    // NatNetLib 3 / python_natnet: the sender block only.
    encode_connect_into(&Connect::emoshift(NatNetVersion::V3_0), false, &mut out)
        .expect("the test's own values are valid");
    assert_eq!(
        decode_command(&out),
        Ok(Command::Connect(Hello {
            natnet_version: Some(NatNetVersion::V3_0),
            bitstream: None,
        }))
    );
    // NatNet 4 with connection options, and the Python SDK's trailing NUL.
    encode_connect_into(&Connect::emoshift(NatNetVersion::V4_1), true, &mut out)
        .expect("the test's own values are valid");
    out.push(0);
    out[2] += 1;
    assert_eq!(
        decode_command(&out),
        Ok(Command::Discovery(Hello {
            natnet_version: Some(NatNetVersion::V4_1),
            bitstream: Some(NatNetVersion::V4_1),
        }))
    );
    // The `natnet` package: "Ping".
    assert_eq!(
        decode_command(b"\x00\x00\x05\x00Ping\0"),
        Ok(Command::Connect(Hello::default()))
    );
}

#[test]
fn requests_are_named_as_motive_names_them() {
    let mut out = Vec::new();
    for (text, want) in [
        (
            "Bitstream,3.1",
            Request::Bitstream(Some(NatNetVersion::V3_1)),
        ),
        (
            "bitstream,4.1.0.0",
            Request::Bitstream(Some(NatNetVersion::V4_1)),
        ),
        ("Bitstream,four", Request::Bitstream(None)),
        ("Bitstream", Request::Bitstream(None)),
        ("FrameRate", Request::FrameRate),
        ("UnitsToMillimeters", Request::UnitsToMillimeters),
        ("TimelinePlay", Request::TimelinePlay),
        ("TimelineStop", Request::TimelineStop),
        ("FrameRate,2", Request::Other(b"FrameRate,2")),
        (
            "SetPlaybackCurrentFrame,0",
            Request::Other(b"SetPlaybackCurrentFrame,0"),
        ),
    ] {
        encode_request_into(text, &mut out).expect("the test's own values are valid");
        assert_eq!(decode_command(&out), Ok(Command::Request(want)), "{text}");
    }
    // NatNetLib's garbage after the NUL is ignored.
    assert_eq!(
        decode_command(b"\x02\x00\x0c\x00FrameRate\0\xff\xee"),
        Ok(Command::Request(Request::FrameRate))
    );
}

#[test]
fn empty_commands_ignore_payloads_and_echo_is_strict() {
    let mut out = Vec::new();
    for (id, want) in [
        (MessageId::KeepAlive, Command::KeepAlive),
        (MessageId::RequestModelDef, Command::RequestModelDef),
        (MessageId::RequestFrameOfData, Command::RequestFrameOfData),
        (MessageId::Disconnect, Command::Disconnect),
    ] {
        encode_empty_into(id, &mut out);
        assert_eq!(decode_command(&out), Ok(want));
        out.push(0);
        out[2] = 1;
        assert_eq!(decode_command(&out), Ok(want));
    }
    encode_echo_request_into(77, &mut out);
    assert_eq!(decode_command(&out), Ok(Command::EchoRequest(77)));
    assert!(decode_command(&out[..8]).is_err());
    assert_eq!(
        decode_command(&[7, 0, 0, 0]),
        Ok(Command::NotACommand(MessageId::FrameOfData))
    );
    assert!(decode_command(&[200, 0, 0, 0]).is_err());
    assert!(decode_command(&[0, 0, 9, 0]).is_err());
}

#[test]
fn replies_decode_as_clients_read_them() {
    let mut out = Vec::new();
    encode_response_f32_into(120.0, &mut out);
    let Ok(Packet::Response(p)) = decode_packet(&out) else {
        panic!("a response");
    };
    assert_eq!(
        response_code(p).map(|c| f32::from_bits(c as u32)),
        Some(120.0)
    );
    encode_response_code_into(0, &mut out);
    assert_eq!(decode_packet(&out), Ok(Packet::Response(&[0, 0, 0, 0])));
    let info = ServerInfo {
        app_name: "emoshift".into(),
        app_version: [0, 1, 0, 0],
        natnet_version: NatNetVersion::V4_1,
        connection: None,
    };
    encode_unrecognized_into(&info, &mut out).expect("the test's own values are valid");
    assert_eq!(out.len(), HEADER_LEN + NAME_LEN + 8);
    assert_eq!(decode_packet(&out), Ok(Packet::UnrecognizedRequest));
}

use crate::natnet::response_code;
