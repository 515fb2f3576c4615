use super::*;

fn raw(server: &str) -> RawNatNetServer {
    RawNatNetServer {
        server: Some(server.into()),
        ..Default::default()
    }
}

#[test]
fn defaults_are_motives_ports_on_loopback() {
    let c = raw("127.0.0.1")
        .validate()
        .expect("the test's own values are valid")
        .expect("the test's own values are valid");
    assert_eq!(
        c.command,
        "127.0.0.1:1510"
            .parse()
            .expect("the test's own values are valid")
    );
    assert_eq!(
        c.data_addr(),
        "127.0.0.1:1511"
            .parse()
            .expect("the test's own values are valid")
    );
    assert_eq!(c.version, NatNetVersion::V4_1);
    assert_eq!(c.multicast, None);
    assert_eq!(c.interface, Ipv4Addr::LOCALHOST);
    let c = raw("127.0.0.1:0")
        .validate()
        .expect("the test's own values are valid")
        .expect("the test's own values are valid");
    assert_eq!(c.data_addr().port(), 0);
}

#[test]
fn multicast_and_version_are_checked() {
    let mut r = raw("127.0.0.1:1512");
    r.multicast = Some("239.255.42.99".into());
    r.version = Some("3.1".into());
    let c = r
        .clone()
        .validate()
        .expect("the test's own values are valid")
        .expect("the test's own values are valid");
    assert_eq!(
        c.multicast,
        Some(
            "239.255.42.99:1513"
                .parse()
                .expect("the test's own values are valid")
        )
    );
    assert_eq!(c.version, NatNetVersion::V3_1);
    r.multicast = Some("10.0.0.1:5000".into());
    assert!(r.clone().validate().is_err());
    r.multicast = None;
    r.version = Some("2.9".into());
    assert!(r.validate().is_err());
    let stray = RawNatNetServer {
        raw: Some(true),
        ..Default::default()
    };
    assert!(stray.validate().is_err());
    assert_eq!(RawNatNetServer::default().validate(), Ok(None));
}
