use super::*;

#[test]
fn sentences_are_two_to_four_seconds_and_co_articulated() {
    for i in 0..20 {
        let s = Sentence::generate(7, i, 20);
        assert!((2.0..=4.3).contains(&s.duration_s), "{}", s.duration_s);
        assert!(!s.brow_events.is_empty());
        // Smooth: no frame-to-frame jump larger than a small fraction of the range at 120 Hz.
        let mut prev = s.speech_at(0.0);
        let mut t = 0.0;
        while t < s.duration_s {
            t += 1.0 / 120.0;
            let cur = s.speech_at(t);
            for k in 0..SPEECH_SOURCES {
                assert!((cur[k] - prev[k]).abs() < 0.2, "jump in source {k} at {t}");
            }
            prev = cur;
        }
    }
}

#[test]
fn sentence_ids_are_padded() {
    assert_eq!(sentence_id(2, 8), "s03");
    assert_eq!(sentence_id(2, 150), "s003");
}
