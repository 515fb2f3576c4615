use super::*;

const WINDOW: SpinWindow = SpinWindow {
    lead: Duration::from_micros(200),
    grace: Duration::from_micros(200),
};

fn us(n: u64) -> Duration {
    Duration::from_micros(n)
}

#[test]
fn a_steady_source_is_polled_for_just_around_its_beat() {
    let t0 = Instant::now();
    let mut c = ArrivalClock::new(WINDOW);
    assert_eq!(c.plan(t0), Wait::Park, "no beat yet");
    let period = us(8_333);
    for k in 0..20u32 {
        // four performers on each tick, 20 µs apart
        for p in 0..4u32 {
            c.frame_arrived(t0 + period * k + us(20) * p);
        }
    }
    let learned = c.period().expect("a period");
    assert!(learned.abs_diff(period) < us(5), "{learned:?}");
    let last = t0 + period * 19;
    assert_eq!(
        c.plan(last + us(100)),
        Wait::ParkUntil(last + learned - us(200))
    );
    assert_eq!(
        c.plan(last + learned - us(150)),
        Wait::PollUntil(last + learned + us(200))
    );
    assert_eq!(c.plan(last + learned + us(250)), Wait::Park, "missed beat");
}

#[test]
fn jitter_pauses_and_start_up_delays_do_not_throw_the_period_off() {
    let t0 = Instant::now();
    let mut c = ArrivalClock::new(WINDOW);
    let mut t = t0;
    for k in 0..64u32 {
        t += if k % 2 == 0 { us(8_000) } else { us(8_666) };
        c.frame_arrived(t);
    }
    t += Duration::from_secs(2); // the performer stops, then resumes
    c.frame_arrived(t);
    let learned = c.period().expect("a period");
    assert!(learned.abs_diff(us(8_333)) <= us(333), "{learned:?}");
    // A start-up delay is forgotten within a few ticks.
    let mut c = ArrivalClock::new(WINDOW);
    c.frame_arrived(t0);
    for k in 0..5u32 {
        c.frame_arrived(t0 + us(30_000) + us(8_333) * k);
    }
    assert_eq!(c.period(), Some(us(8_333)));
}

#[test]
fn polling_is_skipped_when_it_would_cost_too_much_or_is_off() {
    let t0 = Instant::now();
    let mut fast = ArrivalClock::new(WINDOW);
    // interleaved sources: a frame every 2.5 ms, a 400 µs window would be 16 %
    for k in 0..10u32 {
        fast.frame_arrived(t0 + us(2_500) * k);
    }
    assert_eq!(fast.plan(t0 + us(2_500) * 9 + us(2_400)), Wait::Park);
    let mut off = ArrivalClock::new(SpinWindow::OFF);
    for k in 0..10u32 {
        off.frame_arrived(t0 + us(8_333) * k);
    }
    assert_eq!(off.plan(t0 + us(8_333) * 9 + us(8_300)), Wait::Park);
}
