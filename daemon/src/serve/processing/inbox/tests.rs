use std::net::UdpSocket;
use std::time::Duration;

use super::*;

const LONG: Duration = Duration::from_secs(5);

fn inbox() -> (Inbox, Doorbell, UdpSocket, SocketAddr) {
    let socket = UdpSocket::bind("127.0.0.1:0").expect("a loopback socket");
    let addr = socket.local_addr().expect("bound");
    let (inbox, bell) = Inbox::new(socket).expect("an inbox");
    let sender = UdpSocket::bind("127.0.0.1:0").expect("a sender");
    (inbox, bell, sender, addr)
}

/// Datagrams wake the wait and are read in order until none is left; then the wait sleeps.
#[test]
fn datagrams_wake_the_wait_and_are_read_until_none_is_left() {
    let (mut inbox, _bell, sender, addr) = inbox();
    let mut buf = [0u8; 64];
    // Nothing yet: the first look finds the socket empty, then the wait times out.
    assert_eq!(inbox.recv(&mut buf), None);
    assert!(!inbox.wait(Duration::from_millis(20)), "nothing came");
    for byte in [1u8, 2, 3] {
        sender.send_to(&[byte; 4], addr).expect("sent");
    }
    assert!(inbox.wait(LONG), "a datagram wakes the wait");
    let mut got = Vec::new();
    while let Some((len, _)) = inbox.recv(&mut buf) {
        got.push(buf[..len].to_vec());
    }
    assert_eq!(got, [[1u8; 4], [2; 4], [3; 4]]);
    assert!(!inbox.pending(), "read until it would block");
}

/// The bell wakes the wait without a datagram; after shutdown the socket is no longer read.
#[test]
fn the_bell_wakes_the_wait_and_shutdown_stops_reading() {
    let (mut inbox, bell, sender, addr) = inbox();
    let mut buf = [0u8; 64];
    assert_eq!(inbox.recv(&mut buf), None);
    let ringer = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(20));
        bell.ring();
    });
    assert!(inbox.wait(LONG), "the bell wakes the wait");
    ringer.join().expect("the ringer");
    assert!(!inbox.pending(), "a ring is not a datagram");
    inbox.close_socket();
    sender.send_to(b"late", addr).expect("sent");
    assert!(!inbox.wait(Duration::from_millis(20)));
    assert_eq!(inbox.recv(&mut buf), None, "not read after shutdown");
}

/// A wait of a fraction of a millisecond (the timer's, not mio's) ends on its own, nothing
/// having come, and not before its time; again and again, each arming the timer anew.
#[test]
fn a_sub_millisecond_wait_ends_on_the_timer() {
    let (mut inbox, _bell, _sender, _addr) = inbox();
    assert_eq!(inbox.recv(&mut [0u8; 8]), None);
    for _ in 0..3 {
        let wait = Duration::from_micros(1_500);
        let start = std::time::Instant::now();
        assert!(
            !inbox.wait(wait),
            "a timer's expiry is not something that came"
        );
        assert!(start.elapsed() >= wait, "woke after {:?}", start.elapsed());
    }
}
