use super::*;

fn labels(names: &[&str]) -> Vec<String> {
    names.iter().map(|s| s.to_string()).collect()
}

#[test]
fn matches_by_label_with_reorder_absent_and_extra() {
    let map =
        LabelMap::new(&labels(&["a", "b", "c"]), &labels(&["c", "x", "a"])).expect("shared labels");
    assert_eq!(map.model_to_take, vec![Some(2), None, Some(0)]);
    assert_eq!(map.extra, vec![1]);
    assert_eq!(map.absent().collect::<Vec<_>>(), vec![1]);
    let take = [1.0, 1.0, 1.0, 9.0, 9.0, 9.0, 3.0, 3.0, 3.0];
    let mut xyz = [0.0; 9];
    let mut missing = [false; 3];
    map.gather_into(&take, &[false, false, false], &mut xyz, &mut missing);
    assert_eq!(xyz, [3.0, 3.0, 3.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
    assert_eq!(missing, [false, true, false]);
    let (mut xyz2, mut missing2) = ([7.0; 9], [false; 3]);
    map.gather_present_into(&take, &mut xyz2, &mut missing2);
    assert_eq!((xyz2, missing2), (xyz, missing));
}

#[test]
fn same_order_gathers_like_the_general_path() {
    let names = labels(&["a", "b", "c"]);
    let map = LabelMap::new(&names, &names).expect("shared labels");
    let take = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0];
    let (mut fast, mut fast_missing) = ([0.0; 9], [true; 3]);
    map.gather_present_into(&take, &mut fast, &mut fast_missing);
    let (mut slow, mut slow_missing) = ([0.0; 9], [true; 3]);
    map.gather_into(&take, &[false; 3], &mut slow, &mut slow_missing);
    assert_eq!((fast, fast_missing), (take, [false; 3]));
    assert_eq!((slow, slow_missing), (take, [false; 3]));
    // A take with an extra marker first is not in model order.
    let shifted = LabelMap::new(&names, &labels(&["x", "a", "b", "c"])).expect("shared");
    let take4 = [0.0, 0.0, 0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0];
    let (mut xyz, mut missing) = ([0.0; 9], [true; 3]);
    shifted.gather_present_into(&take4, &mut xyz, &mut missing);
    assert_eq!((xyz, missing), (take, [false; 3]));
}

#[test]
fn differences_name_the_absent_and_the_extra_markers() {
    let model = labels(&["a", "b", "c", "d", "e", "f", "g"]);
    let take = labels(&["b", "x", "a"]);
    let map = LabelMap::new(&model, &take).expect("shared markers");
    let d = map.differences(&model, &take);
    assert_eq!(d.absent, labels(&["c", "d", "e", "f", "g"]));
    assert_eq!(d.extra, labels(&["x"]));
    assert_eq!(
        d.describe("model").as_deref(),
        Some("lacks 5 of the model's 7 markers (c, d, e, f, g); has 1 marker the model does not have (x)")
    );
    let take = labels(&["g", "f", "e", "d", "c", "b", "a"]);
    let same = LabelMap::new(&model, &take).expect("the same markers");
    assert!(same.differences(&model, &take).is_empty());
    assert_eq!(same.differences(&model, &take).describe("model"), None);
    let few = labels(&["a"]);
    let one = LabelMap::new(&model, &few).expect("one shared marker");
    let text = one.differences(&model, &few).describe("first take");
    assert_eq!(
        text.as_deref(),
        Some("lacks 6 of the first take's 7 markers (b, c, d, e, f and 1 more)")
    );
}

#[test]
fn no_common_marker_is_an_error() {
    assert_eq!(
        LabelMap::new(&labels(&["a"]), &labels(&["b", "c"])),
        Err(LayoutError::NoCommonMarkers { model: 1, take: 2 })
    );
}
