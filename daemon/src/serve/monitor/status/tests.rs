use super::*;

#[test]
fn the_recent_window_shows_a_jump_the_whole_run_hides() {
    let mut lat = Latency::default();
    let (mut p, s) = (Stats::histogram(), Stats::histogram());
    for _ in 0..100_000 {
        Stats::record(&mut p, 100);
    }
    for _ in 0..=WINDOW_S {
        lat.observe(p.clone(), s.clone());
    }
    for _ in 0..1_000 {
        Stats::record(&mut p, 5_000);
    }
    lat.observe(p.clone(), s.clone());
    let v = lat.value();
    assert_eq!(
        v["processed"]["p50"], 5_003,
        "the last seconds: all slow (5 ms, to 3 digits)"
    );
    assert_eq!(v["processed"]["p99_all"], 100, "since the start: 1 % slow");
    assert_eq!(v["window_s"], WINDOW_S);
}

#[test]
fn health_counts_drops_by_reason_and_lists_the_recording() {
    let mut s = Stats::new();
    s.counters.dropped_stale = 4;
    s.recording = Some(("take.c3d".into(), None));
    let msg = Health::of(&s).into_message(&Latency::default(), MonitorCounters::default());
    let v: Value = serde_json::from_str(&msg).expect("json");
    assert_eq!(v["drops"]["stale"], 4);
    assert_eq!(v["recording"]["path"], "take.c3d");
    assert_eq!(v["type"], "status");
}
