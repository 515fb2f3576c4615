use super::*;

fn at(addr: &str, token: Option<&str>) -> Access {
    Access::new(addr.parse().expect("literal"), token.map(String::from))
}

#[test]
fn on_this_host_no_token_but_the_host_must_be_loopback() {
    let a = at("127.0.0.1:9080", None);
    assert_eq!(a.token(), None);
    for host in [
        "127.0.0.1:9080",
        "localhost:9080",
        "[::1]:9080",
        "LOCALHOST",
    ] {
        assert_eq!(a.check(Some(host), None, None), Verdict::Allow, "{host}");
    }
    for host in ["evil.example:9080", "192.168.1.4:9080"] {
        assert_eq!(a.check(Some(host), None, None), Verdict::BadHost, "{host}");
    }
    assert_eq!(a.check(None, None, None), Verdict::BadHost);
    assert!(a.origin_ok(Some("127.0.0.1:9080"), Some("http://127.0.0.1:9080")));
    assert!(!a.origin_ok(Some("127.0.0.1:9080"), Some("http://evil.example")));
    assert!(!a.origin_ok(Some("evil.example:9080"), Some("http://evil.example:9080")));
    assert!(!a.origin_ok(Some("127.0.0.1:9080"), None));
}

#[test]
fn beyond_this_host_a_random_token_then_a_cookie() {
    let a = at("127.0.0.2:9080", None);
    let token = a.token().expect("generated").to_string();
    assert_eq!(token.len(), 32);
    assert_ne!(Some(token.as_str()), at("0.0.0.0:9080", None).token());
    let host = Some("10.0.0.5:9080");
    assert_eq!(a.check(host, None, None), Verdict::Login { wrong: false });
    let wrong = "token=0123456789abcdef0123456789abcdef";
    assert_eq!(
        a.check(host, Some(wrong), None),
        Verdict::Login { wrong: true }
    );
    let right = format!("x=1&token={token}");
    assert_eq!(a.check(host, Some(&right), None), Verdict::SetCookie);
    let cookie = a.set_cookie().expect("a token");
    let sent = cookie.split(';').next().expect("name=value");
    assert_eq!(
        a.check(host, None, Some(&format!("theme=dark; {sent}"))),
        Verdict::Allow
    );
    let other_page = format!("{COOKIE}_9081={token}");
    assert_eq!(
        a.check(host, None, Some(&other_page)),
        Verdict::Login { wrong: false },
        "another port's page keeps its own cookie"
    );
    let forged = format!("{COOKIE}_9080={}", &token[..31]);
    assert_eq!(
        a.check(host, None, Some(&forged)),
        Verdict::Login { wrong: false }
    );
    assert!(a.origin_ok(host, Some("http://10.0.0.5:9080")));
    assert!(!a.origin_ok(host, Some("http://10.0.0.6:9080")));
}

#[test]
fn a_configured_token_holds_on_loopback_too() {
    let a = at("127.0.0.1:9080", Some("stage-token-0123456789"));
    assert_eq!(
        a.check(Some("127.0.0.1:9080"), None, None),
        Verdict::Login { wrong: false }
    );
    assert_eq!(
        a.check(None, Some("token=stage-token-0123456789"), None),
        Verdict::SetCookie
    );
}
