use super::*;

#[test]
fn levels_are_fixed_for_known_names_and_distinct_for_others() {
    let names: Vec<String> = ["sad", "happy", "angry", "neutral", "frustrated", "calm"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let l = emotion_levels(&names);
    assert_eq!(l, vec![0.5, 1.0, -0.5, 0.0, -1.0, 1.5]);
    let many: Vec<String> = (0..30).map(|i| format!("e{i}")).collect();
    let l = emotion_levels(&many);
    for i in 0..l.len() {
        assert!(!l[..i].contains(&l[i]));
    }
}

#[test]
fn blinks_are_short_spaced_and_peak_near_closed() {
    for seed in 0..20 {
        let ev = blink_events(seed, 30.0);
        assert!(ev.len() >= 4);
        for w in ev.windows(2) {
            let gap = w[1].start_s - w[0].start_s;
            assert!((2.0..6.0).contains(&gap));
        }
        let e = &ev[0];
        let peak = blink_at(&ev, e.start_s + 0.4 * e.duration_s);
        assert!((peak - e.amplitude).abs() < 1e-9);
        assert_eq!(blink_at(&ev, e.start_s - 0.01), 0.0);
    }
}
