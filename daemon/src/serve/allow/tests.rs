use super::*;

fn ip(s: &str) -> IpAddr {
    s.parse().expect("literal address")
}

#[test]
fn networks_contain_their_hosts_only() {
    let lan = Cidr::parse("10.1.0.0/16").expect("valid");
    assert!(lan.contains(ip("10.1.200.3")));
    assert!(!lan.contains(ip("10.2.0.1")));
    assert!(lan.contains(ip("::ffff:10.1.0.9")), "IPv4-mapped");
    assert!(Cidr::parse("0.0.0.0/0")
        .expect("valid")
        .contains(ip("8.8.8.8")));
    assert!(Cidr::parse("192.168.1.7")
        .expect("a host")
        .contains(ip("192.168.1.7")));
    assert!(!Cidr::parse("192.168.1.7")
        .expect("a host")
        .contains(ip("192.168.1.8")));
    assert!(Cidr::parse("fe80::/10")
        .expect("valid")
        .contains(ip("fe80::1")));
    for bad in ["10.0.0.0/33", "x", "10.0.0.0/", "::1/129"] {
        assert!(Cidr::parse(bad).is_err(), "{bad}");
    }
}

#[test]
fn the_default_control_list_is_loopback_and_empty_is_anyone() {
    let l = AllowList::loopback();
    assert!(l.allows(ip("127.0.0.2")) && l.allows(ip("::1")));
    assert!(!l.allows(ip("192.168.0.10")));
    assert!(AllowList::anyone().allows(ip("192.168.0.10")));
}

#[test]
fn loopback_only_is_the_default_and_nothing_wider() {
    assert!(AllowList::loopback().loopback_only());
    assert!(AllowList::parse(&["127.0.0.1"])
        .expect("ok")
        .loopback_only());
    assert!(!AllowList::anyone().loopback_only());
    assert!(!AllowList::parse(&["127.0.0.0/8", "10.0.0.0/8"])
        .expect("ok")
        .loopback_only());
    assert!(!AllowList::parse(&["0.0.0.0/0"])
        .expect("ok")
        .loopback_only());
}
