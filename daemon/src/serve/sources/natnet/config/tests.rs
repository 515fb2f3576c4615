use super::*;

#[test]
fn servers_default_to_the_command_port_and_bad_keys_are_named() {
    let raw = RawNatNet {
        server: Some("10.0.0.5".into()),
        data: Some("239.255.42.99:1511".into()),
        timecode_rate: Some("29.97df".into()),
        names: Some("asset_marker".into()),
        ..RawNatNet::default()
    };
    let c = raw.validate().expect("valid").expect("a server");
    assert_eq!(c.server, "10.0.0.5:1510".parse().expect("addr"));
    assert_eq!(c.timecode_rate, Some(TimecodeRate::DF_29_97));
    assert_eq!(c.naming.separator.as_deref(), Some("_"));
    let bad = |raw: RawNatNet| raw.validate().expect_err("bad").to_string();
    let with = |f: fn(&mut RawNatNet)| {
        let mut r = RawNatNet {
            server: Some("127.0.0.1".into()),
            ..RawNatNet::default()
        };
        f(&mut r);
        r
    };
    assert!(bad(with(|r| r.timecode_rate = Some("25df".into()))).contains("natnet_timecode_rate"));
    assert!(bad(with(|r| r.names = Some("x".into()))).contains("natnet_names"));
    assert!(bad(with(|r| r.data = Some("here".into()))).contains("natnet_data"));
    assert!(bad(with(|r| r.server = Some("motive".into()))).contains("natnet"));
    let stray = RawNatNet {
        data: Some("239.255.42.99:1511".into()),
        ..RawNatNet::default()
    };
    assert!(bad(stray).contains("natnet"));
    assert_eq!(RawNatNet::default().validate(), Ok(None));
}
