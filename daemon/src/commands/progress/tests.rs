use super::*;

#[test]
fn lines_give_totals_rate_and_eta() {
    let mut lines = Lines::new("train", Vec::new(), Duration::ZERO);
    lines.step("statistics", "frames", Some(1_000));
    lines.advance(250);
    lines.note("12 gappy frames");
    lines.step("refinement", "iterations", None);
    lines.advance(3);
    lines.step("restarts", "restarts", None);
    lines.step("whitening", "frames", Some(10));
    lines.advance(4);
    lines.abandon();
    let text = String::from_utf8(lines.into_inner()).expect("utf-8");
    let rows: Vec<&str> = text.lines().collect();
    assert!(
        rows[0].starts_with("train: statistics: 250 / 1,000 frames (25 %), ETA "),
        "{text}"
    );
    assert!(rows[0].contains("frames/s"), "{text}");
    assert!(
        rows[1].starts_with("train: statistics done: 250 frames in "),
        "{text}"
    );
    assert!(rows[1].ends_with("[12 gappy frames]"), "{text}");
    assert!(
        rows[2].starts_with("train: refinement: 3 iterations, "),
        "{text}"
    );
    assert!(
        rows[3].starts_with("train: refinement done: 3 iterations"),
        "{text}"
    );
    assert!(rows[4].starts_with("train: restarts done in "), "{text}");
    // The abandoned step printed its state, never that it was done.
    assert!(
        rows[5].starts_with("train: whitening: 4 / 10 frames"),
        "{text}"
    );
    assert_eq!(rows.len(), 6);
}
