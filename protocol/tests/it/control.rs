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
            profile: Profile::FlatSplit,
            performer: None,
            cookie: None,
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
    assert_eq!(
        e.to_string(),
        "/emotion/ramp: seconds -1 is out of range (0..=60)"
    );
    let e =
        decode_control(&msg("/emotion/amount", vec![OscType::Float(f32::NAN)])).expect_err("nan");
    assert_eq!(
        e.to_string(),
        "/emotion/amount: amount NaN is out of range (0..=1)"
    );
    let e = decode_control(&msg(
        "/component/gain",
        vec![OscType::Int(-2), OscType::Float(1.0)],
    ))
    .expect_err("negative component");
    assert_eq!(
        e.to_string(),
        "/component/gain: component -2 is out of range (>= 0)"
    );
    let e = decode_control(&msg("/unsubscribe", vec![OscType::Int(70_000)])).expect_err("port");
    assert_eq!(
        e.to_string(),
        "/unsubscribe: port 70000 is out of range (1..=65535)"
    );
    let e = decode_control(&msg(
        "/subscribe",
        vec![OscType::Int(9), OscType::String("vmc".into())],
    ))
    .expect_err("profile");
    assert_eq!(e, ControlError::UnknownProfile { name: "vmc".into() });
    for (address, args, text) in [
        (
            "/emotion/amount",
            vec![OscType::Float(5.0)],
            "amount 5 is out of range (0..=1)",
        ),
        (
            "/emotion/amount",
            vec![OscType::Float(-2.0)],
            "amount -2 is out of range (0..=1)",
        ),
        (
            "/emotion/ramp",
            vec![OscType::Float(1e30)],
            "seconds 1000000000000000000000000000000 is out of range (0..=60)",
        ),
        (
            "/component/gain",
            vec![OscType::Int(2), OscType::Float(1e30)],
            "gain 1000000000000000000000000000000 is out of range (-10..=10)",
        ),
        (
            "/emotion/alpha",
            vec![OscType::Int(0), OscType::Float(-1e3)],
            "value -1000 is out of range (-100..=100)",
        ),
        (
            "/emotion/target",
            vec![OscType::String("x".repeat(300))],
            "emotion of 300 bytes is out of range (at most 256 bytes)",
        ),
    ] {
        let e = decode_control(&msg(address, args)).expect_err("out of range");
        assert_eq!(e.to_string(), format!("{address}: {text}"));
    }
    let e = decode_control(&msg("/emotion/targets", vec![])).expect_err("address");
    assert_eq!(e.to_string(), "unknown control address /emotion/targets");
    let e = decode_control(&msg("/status", vec![OscType::Int(1)])).expect_err("args");
    assert_eq!(e.to_string(), "/status takes ,, got ,i");
    let e = decode_control(&msg("/subscribe", vec![OscType::Int(9), OscType::Int(1)]))
        .expect_err("shape");
    assert_eq!(
        e.to_string(),
        "/subscribe takes ,is, ,iss, ,isi or ,issi, got ,ii"
    );
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
    encode_status_into(
        &[("frames_in", 10.into()), ("frames_dropped", 2.into())],
        &mut out,
    );
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

#[test]
fn subscriptions_name_a_performer_and_echo_a_cookie() {
    let args = |extra: Vec<OscType>| {
        let mut v = vec![OscType::Int(9000), OscType::String("compact".into())];
        v.extend(extra);
        msg("/subscribe", v)
    };
    let c = decode_control(&args(vec![
        OscType::String("alice".into()),
        OscType::Int(77),
    ]));
    assert_eq!(
        c,
        Ok(Control::Subscribe {
            port: 9000,
            profile: Profile::Compact,
            performer: Some("alice".into()),
            cookie: Some(77),
        })
    );
    let c = decode_control(&args(vec![OscType::Int(-5)]));
    assert!(matches!(
        c,
        Ok(Control::Subscribe {
            performer: None,
            cookie: Some(-5),
            ..
        })
    ));
}

#[test]
fn the_secret_is_the_last_string_and_only_mutating_controls_need_it() {
    let signed = msg(
        "/record/start",
        vec![
            OscType::String("a.csv".into()),
            OscType::String("s3cret".into()),
        ],
    );
    let (c, ok) = decode_control_with_secret(&signed, "s3cret").expect("valid");
    assert!(ok);
    assert_eq!(
        c,
        Control::RecordStart {
            path: "a.csv".into(),
            raw: None,
            overwrite: false
        }
    );
    // Without the secret the same bytes are a recording with a raw file, not signed.
    let (c, ok) = decode_control_with_secret(&signed, "other").expect("valid");
    assert!(!ok);
    assert!(matches!(c, Control::RecordStart { raw: Some(_), .. }));
    let mut out = Vec::new();
    encode_control_signed_into(&Control::Amount(0.5), "s3cret", &mut out);
    assert_eq!(
        decode_control_with_secret(&out, "s3cret"),
        Ok((Control::Amount(0.5), true))
    );
    assert!(Control::Amount(0.5).is_mutating());
    assert!(!Control::Status.is_mutating());
}

#[test]
fn issue_33_session_controls_round_trip_and_status_is_answered_as_iiisss() {
    use protocol::{encode_session_status_into, SessionControl, SessionStatus};
    for c in SessionControl::ALL {
        let control = Control::Session(c);
        let mut out = Vec::new();
        protocol::encode_control_into(&control, &mut out);
        assert_eq!(decode_control(&out).expect("decodes"), control);
        assert_eq!(control.is_mutating(), c != SessionControl::Status);
    }
    let status = SessionStatus {
        take: 3,
        takes: 32,
        sentence: 1,
        emotion: "sad".into(),
        state: "review".into(),
        text: "The birch canoe slid on the smooth planks.".into(),
    };
    let mut out = Vec::new();
    encode_session_status_into(&status, &mut out);
    assert!(out.starts_with(b"/session/status/confirm\0,iiisss\0"));
    assert_eq!(
        protocol::decode_reply(&out).expect("a reply"),
        protocol::Reply::SessionStatus(status)
    );
    let with_arg = decode_control(&msg("/session/start", vec![OscType::Int(1)]));
    assert!(
        with_arg.is_err(),
        "session controls take no arguments: {with_arg:?}"
    );
}
