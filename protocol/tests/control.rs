//! Control decoding: accepted shapes, typed refusals and their reply text.

use protocol::*;
use rosc::{decoder, encoder, OscMessage, OscPacket, OscType};

fn msg(addr: &str, args: Vec<OscType>) -> Vec<u8> {
    let p = OscPacket::Message(OscMessage {
        addr: addr.into(),
        args,
    });
    encoder::encode(&p).expect("encodable")
}

#[test]
fn hand_typed_senders_may_use_ints_for_floats() {
    let c = decode_control(&msg("/emotion/amount", vec![OscType::Int(1)]));
    assert_eq!(c, Ok(Control::Amount(1.0)));
    let c = decode_control(&msg("/emotion/ramp", vec![OscType::Double(0.5)]));
    assert_eq!(c, Ok(Control::Ramp(0.5)));
    let c = decode_control(&msg("/bypass", vec![OscType::Bool(true)]));
    assert_eq!(c, Ok(Control::Bypass(true)));
    let c = decode_control(&msg(
        "/subscribe",
        vec![OscType::Int(9000), OscType::String("flat-split".into())],
    ));
    assert_eq!(
        c,
        Ok(Control::Subscribe {
            port: 9000,
            profile: Profile::FlatSplit
        })
    );
}

#[test]
fn refusals_name_the_address_and_the_bad_value() {
    let e =
        decode_control(&msg("/emotion/alpha", vec![OscType::Float(1.0)])).expect_err("wrong args");
    assert_eq!(e.to_string(), "/emotion/alpha takes ,if, got ,f");
    let e =
        decode_control(&msg("/emotion/ramp", vec![OscType::Float(-1.0)])).expect_err("negative");
    assert_eq!(e.to_string(), "/emotion/ramp: seconds -1 is out of range");
    let e =
        decode_control(&msg("/emotion/amount", vec![OscType::Float(f32::NAN)])).expect_err("nan");
    assert_eq!(e.to_string(), "/emotion/amount: amount NaN is out of range");
    let e = decode_control(&msg(
        "/component/gain",
        vec![OscType::Int(-2), OscType::Float(1.0)],
    ))
    .expect_err("negative component");
    assert_eq!(
        e.to_string(),
        "/component/gain: component -2 is out of range"
    );
    let e = decode_control(&msg("/unsubscribe", vec![OscType::Int(70_000)])).expect_err("port");
    assert_eq!(e.to_string(), "/unsubscribe: port 70000 is out of range");
    let e = decode_control(&msg(
        "/subscribe",
        vec![OscType::Int(9), OscType::String("vmc".into())],
    ))
    .expect_err("profile");
    assert_eq!(e, ControlError::UnknownProfile { name: "vmc".into() });
    let e = decode_control(&msg("/emotion/targets", vec![])).expect_err("address");
    assert_eq!(e.to_string(), "unknown control address /emotion/targets");
    let e = decode_control(&msg("/status", vec![OscType::Int(1)])).expect_err("args");
    assert_eq!(e.to_string(), "/status takes ,, got ,i");
    let e = decode_control(b"/status\0,\0\0\0\0\0\0\0").expect_err("trailing");
    assert!(
        matches!(e, ControlError::Packet(DecodeError::TrailingBytes { .. })),
        "{e:?}"
    );
}

#[test]
fn replies_are_the_address_plus_confirm_or_an_error() {
    let mut out = Vec::new();
    encode_confirm_into(&Control::Bypass(true), &mut out);
    let m = decode_osc(&out);
    assert_eq!(
        (m.addr.as_str(), m.args),
        ("/bypass/confirm", vec![OscType::Int(1)])
    );
    encode_status_into(&[("frames_in", 10), ("frames_dropped", 2)], &mut out);
    let m = decode_osc(&out);
    assert_eq!(m.addr, "/status/confirm");
    assert_eq!(
        m.args[..2],
        [OscType::String("frames_in".into()), OscType::Long(10)]
    );
    encode_error_into("/x", "nul\0inside", &mut out);
    assert_eq!(
        decode_reply(&out),
        Ok(Reply::Error {
            address: "/x".into(),
            message: "nul?inside".into()
        })
    );
}

#[test]
fn labels_and_controls_inside_bundles_are_reachable() {
    let inner = msg("/emotion/target", vec![OscType::String("joy".into())]);
    let p = OscPacket::Bundle(rosc::OscBundle {
        timetag: (5, 6).into(),
        content: vec![OscPacket::Message(OscMessage {
            addr: "/emotion/target".into(),
            args: vec![OscType::String("joy".into())],
        })],
    });
    let bytes = encoder::encode(&p).expect("encodable");
    let msgs: Vec<_> = messages(&bytes, &Limits::default())
        .expect("valid")
        .collect();
    assert_eq!(msgs.len(), 1);
    assert_eq!(msgs[0].bytes, inner.as_slice());
    assert_eq!(
        msgs[0].timetag,
        Some(TimeTag {
            seconds: 5,
            fraction: 6
        })
    );
    assert_eq!(
        decode_control(msgs[0].bytes),
        Ok(Control::Target("joy".into()))
    );
    assert!(matches!(
        decode_control(&bytes),
        Err(ControlError::Packet(DecodeError::BadAddress { .. }))
    ));
}

/// The message in `bytes`, decoded by rosc (the test's independent reader).
fn decode_osc(bytes: &[u8]) -> OscMessage {
    match decoder::decode_udp(bytes) {
        Ok((_, OscPacket::Message(m))) => m,
        other => panic!("not one message: {other:?}"),
    }
}
