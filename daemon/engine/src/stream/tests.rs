use std::sync::Arc;

use super::*;
use crate::synthetic::random_model;

#[test]
fn order_counts_duplicates_and_stale_and_restarts_far_jumps() {
    let model = Arc::new(random_model(4, 2, 1));
    let labels: Arc<[String]> = model.labels().into();
    let who = Identity::new(0, "test");
    let mut s = Stream::new(who, model, None, &labels, 1.0).expect("same labels");
    assert_eq!(s.check_order(10), Order::Next { frames: 1 });
    assert_eq!(s.check_order(12), Order::Next { frames: 2 });
    assert_eq!(s.check_order(12), Order::Duplicate);
    assert_eq!(s.check_order(11), Order::Stale);
    assert_eq!(s.check_order(13), Order::Next { frames: 1 });
    assert_eq!(s.check_order(-1000), Order::Restart);
    assert_eq!(s.check_order(-999), Order::Next { frames: 1 });
    assert_eq!((s.duplicates, s.stale), (1, 1));
}

#[test]
fn a_source_restarted_near_where_it_stopped_is_taken_again_after_a_short_run() {
    let model = Arc::new(random_model(4, 2, 1));
    let labels: Arc<[String]> = model.labels().into();
    let who = Identity::new(0, "test");
    let mut s = Stream::new(who, model, None, &labels, 1.0).expect("same labels");
    for n in 1..=240 {
        assert!(matches!(s.check_order(n), Order::Next { .. }));
    }
    // Restarted from 1: within RESTART_FRAMES of 240, so not a far jump. Two frames are taken
    // for late ones, the third in a row counting up is the restart.
    assert_eq!(s.check_order(1), Order::Stale);
    assert_eq!(s.check_order(2), Order::Stale);
    assert_eq!(s.check_order(3), Order::Restart);
    assert_eq!(s.check_order(4), Order::Next { frames: 1 });
    assert_eq!(s.stale, 2);
    // Late frames one at a time between newer ones stay late, however many.
    for n in 5..100 {
        assert!(matches!(s.check_order(n + 1), Order::Next { .. }));
        assert_eq!(s.check_order(n), Order::Stale, "frame {n}");
    }
    // And two late frames in a row that do not follow each other are not a run.
    assert_eq!(s.check_order(90), Order::Stale);
    assert_eq!(s.check_order(50), Order::Stale);
    assert_eq!(s.check_order(70), Order::Stale);
    assert_eq!(s.check_order(101), Order::Next { frames: 1 });
}
