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
