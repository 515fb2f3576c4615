use protocol::{Control, Profile};

use super::*;

/// What the OSC output does with `/subscribe` and `/unsubscribe`: the requester's own IP, at
/// the port it names.
fn control(
    c: &mut Subscribers<Profile>,
    now: Instant,
    peer: SocketAddr,
    msg: &Control,
) -> Result<Change, SubscribeError> {
    match msg {
        Control::Subscribe {
            port,
            profile,
            performer,
            ..
        } => c.subscribe(
            now,
            SocketAddr::new(peer.ip(), *port),
            *profile,
            performer.as_deref(),
        ),
        Control::Unsubscribe { port } => c.unsubscribe(SocketAddr::new(peer.ip(), *port)),
        _ => unreachable!("a subscription message"),
    }
}

fn addr(s: &str) -> SocketAddr {
    s.parse().expect("literal address")
}

fn sub(port: u16) -> Control {
    Control::Subscribe {
        port,
        profile: Profile::Compact,
        performer: None,
        cookie: None,
    }
}

fn clients(statics: &[(SocketAddr, Profile)], max_dynamic: usize) -> Subscribers<Profile> {
    Subscribers::new(statics, max_dynamic, 3, DEFAULT_LEASE)
}

#[test]
fn subscribe_goes_to_the_requesters_own_ip_and_is_capped() {
    let now = Instant::now();
    let mut c = clients(&[(addr("239.1.2.3:9000"), Profile::Compact)], 2);
    let peer = addr("127.0.0.5:40000");
    assert_eq!(
        control(&mut c, now, peer, &sub(7000)),
        Ok(Change::Added(addr("127.0.0.5:7000")))
    );
    assert_eq!(
        control(&mut c, now, peer, &sub(7000)),
        Ok(Change::Renewed(addr("127.0.0.5:7000")))
    );
    control(&mut c, now, peer, &sub(7001)).expect("room for two");
    assert_eq!(
        control(&mut c, now, peer, &sub(7002)),
        Err(SubscribeError::Full { max: 2 })
    );
    assert_eq!(c.len(), 3, "the static multicast one does not count");
    assert_eq!(
        control(&mut c, now, peer, &Control::Unsubscribe { port: 7000 }),
        Ok(Change::Removed(addr("127.0.0.5:7000")))
    );
}

#[test]
fn repeated_failures_drop_a_dynamic_subscriber_even_when_interleaved_with_successes() {
    let now = Instant::now();
    let mut c = clients(&[], 16);
    control(&mut c, now, addr("127.0.0.1:1"), &sub(9)).expect("room");
    assert_eq!(c.handle_send(0, false, now), SendOutcome::Failed);
    assert_eq!(c.handle_send(0, true, now), SendOutcome::Sent);
    assert_eq!(c.handle_send(0, false, now), SendOutcome::Failed);
    assert_eq!(c.handle_send(0, false, now), SendOutcome::Dropped);
    assert!(c.is_empty());
}

#[test]
fn a_static_target_is_never_dropped_and_is_retried_on_a_bounded_back_off() {
    let t0 = Instant::now();
    let mut c = clients(&[(addr("127.0.0.1:9"), Profile::Compact)], 16);
    let stream = (0, "alice");
    let mut now = t0;
    let mut longest = Duration::ZERO;
    // Unreachable for a while: every send fails.
    for _ in 0..200 {
        if c.plan(0, now, stream, false).send {
            if let SendOutcome::BackingOff(d) = c.handle_send(0, false, now) {
                longest = longest.max(d);
            }
        }
        now += Duration::from_millis(8);
    }
    assert_eq!(c.len(), 1, "static targets stay");
    assert_eq!(longest, MAX_BACKOFF);
    assert!(c.get(0).expect("there").is_backing_off());
    assert!(
        !c.plan(0, now, stream, false).send,
        "waits out its back-off"
    );
    // It starts listening: the next retry goes through, with the labels first.
    now += MAX_BACKOFF;
    let plan = c.plan(0, now, stream, false);
    assert!(plan.send && plan.labels);
    assert_eq!(c.handle_send(0, true, now), SendOutcome::Recovered);
    for _ in 0..100 {
        now += Duration::from_millis(8);
        let plan = c.plan(0, now, stream, false);
        assert!(plan.send && !plan.labels);
        assert_eq!(c.handle_send(0, true, now), SendOutcome::Sent);
    }
}

#[test]
fn a_performer_filter_and_labels_before_the_first_frame_of_each_stream() {
    let now = Instant::now();
    let mut c = clients(&[], 16);
    let only_bob = Control::Subscribe {
        port: 7000,
        profile: Profile::Compact,
        performer: Some("bob".into()),
        cookie: None,
    };
    control(&mut c, now, addr("127.0.0.1:1"), &only_bob).expect("room");
    control(&mut c, now, addr("127.0.0.1:1"), &sub(7001)).expect("room");
    let alice = (0, "alice");
    let bob = (1, "bob");
    assert!(!c.plan(0, now, alice, false).send);
    assert_eq!(
        c.plan(0, now, bob, false),
        Plan {
            send: true,
            labels: true
        }
    );
    assert_eq!(
        c.plan(0, now, bob, false),
        Plan {
            send: true,
            labels: false
        }
    );
    assert_eq!(
        c.plan(0, now, bob, true),
        Plan {
            send: true,
            labels: true
        }
    );
    assert_eq!(
        c.plan(1, now, alice, false),
        Plan {
            send: true,
            labels: true
        }
    );
    assert_eq!(
        c.plan(1, now, bob, false),
        Plan {
            send: true,
            labels: true
        }
    );
    assert_eq!(
        c.plan(1, now, alice, false),
        Plan {
            send: true,
            labels: false
        }
    );
}

#[test]
fn dynamic_subscriptions_expire_unless_renewed_static_ones_do_not() {
    let now = Instant::now();
    let lease = Duration::from_secs(2);
    let mut c = Subscribers::new(&[(addr("127.0.0.1:9"), Profile::Compact)], 16, 3, lease);
    let peer = addr("127.0.0.1:1");
    control(&mut c, now, peer, &sub(7000)).expect("room");
    control(&mut c, now, peer, &sub(7001)).expect("room");
    assert!(c.poll_expired(now + Duration::from_secs(1)).is_empty());
    control(&mut c, now + Duration::from_secs(1), peer, &sub(7001)).expect("renewed");
    assert_eq!(c.poll_expired(now + lease), vec![addr("127.0.0.1:7000")]);
    assert_eq!(c.len(), 2);
    assert_eq!(
        control(&mut c, now, peer, &Control::Unsubscribe { port: 9 }),
        Err(SubscribeError::Static {
            addr: addr("127.0.0.1:9")
        })
    );
}
