//! The replay schedule on a fake clock: no sockets, no sleeps.
#![allow(clippy::unwrap_used)] // a failed unwrap is a failed test

use std::time::Duration;

use replay::pacer::{Action, FrameSend, Pacer, PacerError, PacerOptions};

fn us(v: u64) -> Duration {
    Duration::from_micros(v)
}

/// Drives a pacer with a punctual fake clock (it wakes exactly at each `Sleep` deadline) until
/// `Done` or `max_actions`, returning the actions with the time each was taken.
fn run_punctual(pacer: &mut Pacer, start: Duration, max_actions: usize) -> Vec<(Duration, Action)> {
    let mut now = start;
    let mut out = Vec::new();
    for _ in 0..max_actions {
        let a = pacer.poll(now);
        out.push((now, a));
        match a {
            Action::Sleep { until } => {
                assert!(until > now, "a sleep must move time forward");
                now = until;
            }
            Action::Done => break,
            _ => {}
        }
    }
    out
}

fn frames(actions: &[(Duration, Action)]) -> Vec<FrameSend> {
    actions
        .iter()
        .filter_map(|(_, a)| match a {
            Action::SendFrame(f) => Some(*f),
            _ => None,
        })
        .collect()
}

fn opts() -> PacerOptions {
    PacerOptions::default()
}

#[test]
fn no_drift_over_a_million_frames() {
    let n = 1_000_000;
    let mut pacer = Pacer::new(120.0, n, opts()).unwrap();
    let start = Duration::from_secs(5);
    let mut now = start;
    let mut sent = 0u64;
    let mut last_due = Duration::ZERO;
    loop {
        match pacer.poll(now) {
            Action::SendFrame(f) => {
                assert_eq!(
                    f.due, now,
                    "a punctual clock releases frames exactly on time"
                );
                sent += 1;
                last_due = f.due;
            }
            Action::Sleep { until } => now = until,
            Action::SendLabels => {}
            Action::Done => break,
        }
    }
    assert_eq!(sent, n as u64);
    // Frame 999,999 is due 999,999 / 120 s after the start, to the nanosecond.
    let exact_ns = 999_999u128 * 1_000_000_000 / 120;
    let got_ns = (last_due - start).as_nanos();
    assert!(got_ns.abs_diff(exact_ns) <= 1, "{got_ns} vs {exact_ns}");
    let s = pacer.summary();
    assert_eq!((s.late_frames, s.skipped_frames), (0, 0));
    assert_eq!(s.max_lateness, Duration::ZERO);
    // Labels every second of an 8,333.3 s replay: at 0, 1, ..., 8333 s.
    assert_eq!(s.labels_sent, 8_334);
}

#[test]
fn speed_two_halves_the_period() {
    let options = PacerOptions {
        speed: 2.0,
        ..opts()
    };
    let mut pacer = Pacer::new(100.0, 5, options).unwrap();
    let sent = frames(&run_punctual(&mut pacer, Duration::ZERO, 100));
    let dues: Vec<_> = sent.iter().map(|f| f.due).collect();
    assert_eq!(dues, [us(0), us(5_000), us(10_000), us(15_000), us(20_000)]);
    // Capture times stay in take time: speed changes when frames leave, not what they say.
    let times: Vec<_> = sent.iter().map(|f| f.capture_time_us).collect();
    assert_eq!(times, [0, 10_000, 20_000, 30_000, 40_000]);
}

#[test]
fn start_frame_is_honoured_and_numbers_follow_the_take() {
    let options = PacerOptions {
        start_frame: 7,
        first_frame_number: 1,
        ..opts()
    };
    let mut pacer = Pacer::new(120.0, 10, options).unwrap();
    let actions = run_punctual(&mut pacer, Duration::ZERO, 100);
    let sent = frames(&actions);
    let got: Vec<_> = sent.iter().map(|f| (f.index, f.frame_number)).collect();
    assert_eq!(got, [(7, 8), (8, 9), (9, 10)]);
    assert_eq!(
        sent[0].due,
        Duration::ZERO,
        "the first frame sent is due at the start"
    );
    assert_eq!(
        sent[0].capture_time_us, 58_333,
        "take time of index 7 at 120 Hz"
    );
    assert_eq!(actions.last().unwrap().1, Action::Done);
    let err = Pacer::new(
        120.0,
        10,
        PacerOptions {
            start_frame: 10,
            ..opts()
        },
    )
    .unwrap_err();
    assert_eq!(err, PacerError::StartPastEnd { start: 10, last: 9 });
}

#[test]
fn looping_wraps_indices_and_keeps_numbers_increasing() {
    let options = PacerOptions {
        looping: true,
        start_frame: 2,
        first_frame_number: 100,
        ..opts()
    };
    let mut pacer = Pacer::new(10.0, 4, options).unwrap();
    let actions = run_punctual(&mut pacer, Duration::ZERO, 40);
    assert!(
        actions.iter().all(|(_, a)| *a != Action::Done),
        "looping never ends"
    );
    let sent = frames(&actions);
    assert!(sent.len() >= 10);
    let indices: Vec<_> = sent.iter().take(10).map(|f| f.index).collect();
    assert_eq!(indices, [2, 3, 0, 1, 2, 3, 0, 1, 2, 3]);
    for w in sent.windows(2) {
        assert_eq!(w[1].frame_number, w[0].frame_number + 1);
        assert_eq!(w[1].capture_time_us - w[0].capture_time_us, 100_000);
        assert_eq!(w[1].due - w[0].due, Duration::from_millis(100));
    }
    assert_eq!(sent[0].frame_number, 102);
    assert_eq!(
        sent[2].frame_number, 104,
        "the second loop continues the numbering"
    );
}

#[test]
fn labels_first_then_every_second() {
    let mut pacer = Pacer::new(4.0, 12, opts()).unwrap();
    let actions = run_punctual(&mut pacer, Duration::from_millis(300), 100);
    assert_eq!(
        actions[0].1,
        Action::SendLabels,
        "labels before the first frame"
    );
    let label_times: Vec<_> = actions
        .iter()
        .filter(|(_, a)| *a == Action::SendLabels)
        .map(|(t, _)| *t - Duration::from_millis(300))
        .collect();
    // 12 frames at 4 Hz span 2.75 s: labels at 0, 1 and 2 s.
    let secs: Vec<_> = (0..3).map(Duration::from_secs).collect();
    assert_eq!(label_times, secs);
    // At 1 s a frame is due too: the labels go first.
    let at_one: Vec<_> = actions
        .iter()
        .filter(|(t, a)| *t == Duration::from_millis(1_300) && !matches!(a, Action::Sleep { .. }))
        .map(|(_, a)| *a)
        .collect();
    assert_eq!(at_one[0], Action::SendLabels);
    assert!(matches!(at_one[1], Action::SendFrame(f) if f.index == 4));
}

#[test]
fn a_late_poll_sends_at_once_and_counts_as_late() {
    let mut pacer = Pacer::new(100.0, 3, opts()).unwrap();
    assert_eq!(pacer.poll(us(0)), Action::SendLabels);
    assert!(matches!(pacer.poll(us(0)), Action::SendFrame(f) if f.index == 0));
    assert_eq!(pacer.poll(us(1)), Action::Sleep { until: us(10_000) });
    // 300 µs late: within the 500 µs allowance.
    match pacer.poll(us(10_300)) {
        Action::SendFrame(f) => assert_eq!((f.index, f.lateness), (1, us(300))),
        other => panic!("expected frame 1, got {other:?}"),
    }
    // 2 ms late: sent at once, counted.
    match pacer.poll(us(22_000)) {
        Action::SendFrame(f) => assert_eq!((f.index, f.lateness), (2, us(2_000))),
        other => panic!("expected frame 2, got {other:?}"),
    }
    assert_eq!(pacer.poll(us(22_001)), Action::Done);
    let s = pacer.summary();
    assert_eq!((s.frames_sent, s.late_frames, s.skipped_frames), (3, 1, 0));
    assert_eq!(s.max_lateness, us(2_000));
    assert_eq!(s.total_lateness, us(2_300));
}

#[test]
fn a_short_stall_sends_the_overdue_frames_back_to_back() {
    let options = PacerOptions {
        max_behind_frames: 5,
        ..opts()
    };
    let mut pacer = Pacer::new(100.0, 20, options).unwrap();
    assert_eq!(pacer.poll(us(0)), Action::SendLabels);
    // Stalled until 50 ms: frames 0..=5 are due, 5 behind the first: all sent, none skipped.
    let now = us(50_000);
    let burst: Vec<_> = (0..6)
        .map(|_| match pacer.poll(now) {
            Action::SendFrame(f) => f.index,
            other => panic!("expected a frame, got {other:?}"),
        })
        .collect();
    assert_eq!(burst, [0, 1, 2, 3, 4, 5]);
    assert_eq!(pacer.poll(now), Action::Sleep { until: us(60_000) });
    assert_eq!(pacer.summary().skipped_frames, 0);
    assert_eq!(pacer.summary().late_frames, 5, "frame 5 was on time");
}

#[test]
fn a_long_stall_skips_to_the_present_and_counts_the_skipped() {
    let options = PacerOptions {
        max_behind_frames: 5,
        first_frame_number: 1,
        ..opts()
    };
    let mut pacer = Pacer::new(100.0, 100, options).unwrap();
    assert_eq!(pacer.poll(us(0)), Action::SendLabels);
    assert!(matches!(pacer.poll(us(0)), Action::SendFrame(f) if f.index == 0));
    // Stalled until 305 ms: frames 1..=30 are overdue; skip 1..=29, send 30 (5 ms late).
    match pacer.poll(us(305_000)) {
        Action::SendFrame(f) => {
            assert_eq!((f.index, f.frame_number), (30, 31));
            assert_eq!(f.lateness, us(5_000));
        }
        other => panic!("expected frame 30, got {other:?}"),
    }
    assert_eq!(
        pacer.poll(us(305_000)),
        Action::Sleep { until: us(310_000) }
    );
    let s = pacer.summary();
    assert_eq!((s.frames_sent, s.skipped_frames, s.late_frames), (2, 29, 1));
}

#[test]
fn a_stall_past_the_end_finishes_the_take() {
    let options = PacerOptions {
        max_behind_frames: 2,
        ..opts()
    };
    let mut pacer = Pacer::new(100.0, 10, options).unwrap();
    assert_eq!(pacer.poll(us(0)), Action::SendLabels);
    assert!(matches!(pacer.poll(us(0)), Action::SendFrame(_)));
    // At 10 s, the one-second labels are due first, then the take is long over.
    assert_eq!(pacer.poll(Duration::from_secs(10)), Action::SendLabels);
    assert_eq!(pacer.poll(Duration::from_secs(10)), Action::Done);
    let s = pacer.summary();
    assert_eq!((s.frames_sent, s.skipped_frames), (1, 9));
    assert_eq!(s.labels_sent, 2, "one send covers every missed second");
}

#[test]
fn bad_schedules_are_rejected() {
    let bad_speed = PacerOptions {
        speed: 0.0,
        ..opts()
    };
    assert_eq!(
        Pacer::new(120.0, 5, bad_speed).unwrap_err(),
        PacerError::BadSpeed(0.0)
    );
    assert!(matches!(
        Pacer::new(f64::NAN, 5, opts()),
        Err(PacerError::BadRate(_))
    ));
    assert_eq!(
        Pacer::new(120.0, 0, opts()).unwrap_err(),
        PacerError::NoFrames
    );
}
