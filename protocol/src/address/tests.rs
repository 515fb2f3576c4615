use super::*;

#[test]
fn routes_known_addresses_only() {
    assert_eq!(Address::parse("/mocap/frame"), Some(Address::Frame));
    assert_eq!(Address::parse("/status"), Some(Address::Control));
    assert_eq!(Address::parse("/status/confirm"), Some(Address::Confirm));
    assert_eq!(Address::parse("/mocap/frame/confirm"), None);
    assert_eq!(Address::parse("/mocap/frames"), None);
}
