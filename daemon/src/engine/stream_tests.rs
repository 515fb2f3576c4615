use std::sync::Arc;

use ica_core::model::Role;

use super::*;
use crate::synthetic::random_model;

#[test]
fn order_counts_duplicates_and_stale_and_restarts_far_jumps() {
    let model = Arc::new(random_model(4, 2, 1));
    let labels: Vec<String> = model.labels().to_vec();
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
fn labelled_components_get_blend_names() {
    let mut model = random_model(6, 5, 1);
    for (k, role) in [
        Role::Emotion,
        Role::Speech,
        Role::Other,
        Role::Speech,
        Role::Eyelids,
    ]
    .into_iter()
    .enumerate()
    {
        model.set_role(k, role).expect("in range");
    }
    let names = vmc_names(&model);
    let expected = [
        ("emotion", 0),
        ("speech1", 1),
        ("speech2", 3),
        ("eyelids", 4),
    ];
    let got: Vec<(&str, usize)> = names.iter().map(|(n, k)| (n.as_str(), *k)).collect();
    assert_eq!(got, expected);
}
