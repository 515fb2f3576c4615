use super::*;

fn names(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

#[test]
fn known_points_are_well_separated() {
    for (dims, known) in [
        (2, KNOWN_POINTS_2.iter().map(|(_, p)| p.to_vec()).collect()),
        (3, KNOWN_POINTS_3.iter().map(|(_, p)| p.to_vec()).collect()),
    ] {
        let known: Vec<Vec<f64>> = known;
        for (i, a) in known.iter().enumerate() {
            assert_eq!(a.len(), dims);
            for b in &known[..i] {
                assert!(distance(a, b) > 0.8, "{a:?} vs {b:?}");
            }
        }
    }
}

#[test]
fn spare_points_keep_their_distance_from_all_others() {
    for dims in 1..=3 {
        let mut list = names(&["calm", "neutral", "sad", "happy", "angry", "fear"]);
        list.extend((0..30).map(|i| format!("e{i}")));
        // An explicit point off the lattice, close to happy (explicit points are the
        // user's choice; only spare points keep their distance).
        let explicit = [EmotionPoint {
            name: "calm".into(),
            point: vec![0.8; dims],
        }];
        let p = emotion_points(&list, dims, &explicit);
        assert_eq!(p[0], vec![0.8; dims]);
        let spare = |i: usize| i != 0 && known_point(&list[i], dims).is_none();
        assert!((0..list.len()).filter(|&i| spare(i)).count() >= 30);
        for (i, a) in p.iter().enumerate() {
            assert_eq!(a.len(), dims);
            for (j, b) in p[..i].iter().enumerate() {
                if spare(i) || spare(j) {
                    let d = distance(a, b);
                    assert!(d >= SPARE_SEPARATION - 1e-9, "{dims}: {a:?} vs {b:?}");
                }
            }
        }
    }
}

#[test]
fn one_direction_keeps_the_historic_levels() {
    let p = emotion_points(
        &names(&["sad", "happy", "angry", "neutral", "frustrated", "calm"]),
        1,
        &[],
    );
    let l: Vec<f64> = p.iter().map(|v| v[0]).collect();
    assert_eq!(l, vec![0.5, 1.0, -0.5, 0.0, -1.0, 1.5]);
}

#[test]
fn points_parse_from_name_equals_coordinates() {
    let p: EmotionPoint = "sad=-0.6, -0.8".parse().expect("valid");
    assert_eq!(p.name, "sad");
    assert_eq!(p.point, vec![-0.6, -0.8]);
    for bad in ["sad", "sad=", "sad=1,x", "sad=nan", "sad=1,,2"] {
        let err = bad.parse::<EmotionPoint>().expect_err("invalid");
        assert!(err.to_string().contains(bad), "{err}");
    }
}

#[test]
fn blends_weigh_points() {
    let (a, b) = ([1.0, 0.0], [0.0, 2.0]);
    let v = blend(2, [(&a[..], 0.5), (&b[..], 0.25)]).expect("same dims");
    assert_eq!(v, vec![0.5, 0.5]);
    assert_eq!(blend(3, [(&a[..], 1.0)]), None);
}
