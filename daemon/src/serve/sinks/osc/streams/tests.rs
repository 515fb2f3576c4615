use ica_core::model::Role;

use super::*;
use engine::synthetic::random_model;

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

/// Issue 37: `vmc_names` maps the default blend names to a receiver's; the others stay.
#[test]
fn vmc_names_rename_the_blend_names_a_receiver_wants() {
    let mut model = random_model(6, 3, 2);
    for (k, role) in [Role::Emotion, Role::Speech, Role::Eyelids]
        .into_iter()
        .enumerate()
    {
        model.set_role(k, role).expect("in range");
    }
    let rename = [("emotion".to_string(), "Joy".to_string())].into();
    let model = Arc::new(model);
    let names = StreamNames::new(0, Some(&model), model.labels(), &rename);
    let got: Vec<(&str, usize)> = names.vmc.iter().map(|(n, k)| (n.as_str(), *k)).collect();
    assert_eq!(got, [("Joy", 0), ("speech", 1), ("eyelids", 2)]);
}
