use super::*;

#[test]
fn defaults_bind_loopback_and_unknown_keys_are_named() {
    let c = RawConfig::from_toml("model = \"m.json\"")
        .expect("valid")
        .validate()
        .expect("valid");
    assert!(c.listen.ip().is_loopback() && c.control.ip().is_loopback());
    assert_eq!(c.max_subscribers, 16);
    let e = RawConfig::from_toml("model = \"m.json\"\nlisten_port = 3").expect_err("unknown");
    assert!(e.to_string().contains("listen_port"), "{e}");
}

#[test]
fn the_example_config_parses_and_holds_the_defaults() {
    let text = include_str!("../../../../docs/emoshift.toml");
    let c = RawConfig::from_toml(text)
        .expect("the example parses")
        .validate()
        .expect("the example is valid");
    let d = RawConfig {
        model: Some("model.json".into()),
        ..RawConfig::default()
    };
    assert_eq!(c, d.validate().expect("defaults are valid"));
}

#[test]
fn send_entries_take_a_profile_and_bad_values_are_named() {
    assert_eq!(
        parse_send("239.0.0.1:9100:flat-split"),
        Ok(("239.0.0.1:9100".parse().expect("addr"), Profile::FlatSplit))
    );
    assert_eq!(parse_send("[::1]:9100").map(|s| s.1), Ok(Profile::Compact));
    assert!(matches!(
        parse_send("127.0.0.1:9:loud"),
        Err(ConfigError::Profile { .. })
    ));
    let raw = RawConfig {
        model: Some("m".into()),
        lowpass_s: Some(-1.0),
        ..RawConfig::default()
    };
    assert!(raw
        .validate()
        .expect_err("negative")
        .to_string()
        .contains("lowpass_s"));
    let raw = RawConfig {
        model: Some("m".into()),
        poll_window_us: Some(5_000),
        ..RawConfig::default()
    };
    assert!(raw
        .validate()
        .expect_err("a 5 ms window would poll most of the period")
        .to_string()
        .contains("poll_window_us"));
    // Without a model the daemon starts and passes frames through (issue 37).
    let none = RawConfig::default().validate().expect("no model is valid");
    assert_eq!(none.model, None);
    assert_eq!(
        none.passthrough_rate_hz,
        engine::pipeline::DEFAULT_PASSTHROUGH_RATE_HZ
    );
    let zero = RawConfig {
        passthrough_rate_hz: Some(0.0),
        ..RawConfig::default()
    };
    assert!(zero
        .validate()
        .expect_err("a rate of 0")
        .to_string()
        .contains("passthrough_rate_hz"));
}

#[test]
fn stage_keys_are_checked_and_named() {
    let c = RawConfig::from_toml(
        "model = \"m.json\"\nsubscription_lease_s = 3.0\ncontrol_allow = [\"10.0.0.0/8\"]\n\
         frames_allow = [\"192.168.1.7\"]\ncontrol_secret = \"k\"\nmax_model_mb = 8\n",
    )
    .expect("valid")
    .validate()
    .expect("valid");
    assert_eq!(c.lease, Duration::from_secs(3));
    assert!(c.control_allow.allows("10.1.2.3".parse().expect("ip")));
    assert!(
        !c.control_allow.allows("127.0.0.1".parse().expect("ip")),
        "replaces loopback"
    );
    assert!(!c.frames_allow.allows("192.168.1.8".parse().expect("ip")));
    assert_eq!(c.control_secret.as_deref(), Some("k"));
    assert_eq!(c.max_model_bytes, 8 << 20);
    for (text, key) in [
        ("subscription_lease_s = 0.1", "subscription_lease_s"),
        ("control_allow = [\"10.0.0.0/40\"]", "control_allow"),
        ("control_secret = \"\"", "control_secret"),
        ("max_model_mb = 0", "max_model_mb"),
    ] {
        let e = RawConfig::from_toml(&format!("model = \"m\"\n{text}\n"))
            .expect("parses")
            .validate()
            .expect_err("out of range");
        assert!(e.to_string().contains(key), "{e}");
    }
    let e = RawConfig::from_toml("model = \"m\"\n\nqueue = \"big\"\n").expect_err("type");
    assert_eq!(
        e.to_string(),
        "line 3, key queue: invalid type: string \"big\", expected usize"
    );
}

#[test]
fn the_frame_and_control_sockets_need_their_own_ports() {
    let validate = |text: &str| {
        RawConfig::from_toml(&format!("model = \"m\"\n{text}\n"))
            .expect("parses")
            .validate()
    };
    for clash in [
        "listen = \"127.0.0.1:9300\"\ncontrol = \"127.0.0.1:9300\"",
        "listen = \"0.0.0.0:9300\"\ncontrol = \"127.0.0.1:9300\"",
    ] {
        let e = validate(clash).expect_err("one port");
        assert!(e.to_string().contains("share a port"), "{e}");
    }
    // Another address of the loopback network, or another family, binds beside it.
    for apart in [
        "listen = \"127.0.0.1:9300\"\ncontrol = \"127.0.0.2:9300\"",
        "listen = \"[::1]:9300\"\ncontrol = \"127.0.0.1:9300\"",
        "listen = \"127.0.0.1:9300\"\ncontrol = \"127.0.0.1:9301\"",
    ] {
        validate(apart).expect("own sockets");
    }
}

#[test]
fn natnet_server_keys_reach_the_server_config() {
    let text = "model = \"m.json\"\nnatnet_server = \"127.0.0.1:1512\"\n\
                natnet_server_multicast = \"239.255.42.100\"\nnatnet_server_raw = true\n";
    let c = RawConfig::from_toml(text)
        .expect("parses")
        .validate()
        .expect("valid");
    let n = c.natnet_server.expect("a NatNet server");
    assert_eq!(n.command, "127.0.0.1:1512".parse().expect("addr"));
    assert_eq!(
        n.multicast,
        Some("239.255.42.100:1513".parse().expect("addr"))
    );
    assert!(n.raw);
    let text = "model = \"m.json\"\nnatnet_server_raw = true\n";
    let e = RawConfig::from_toml(text).expect("parses").validate();
    assert!(e.is_err(), "a server key without natnet_server is named");
}
