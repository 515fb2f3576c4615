use super::all_finite;

#[test]
fn all_finite_finds_any_bad_value_in_lanes_and_tail() {
    for len in 0..21 {
        let mut v: Vec<f32> = (0..len).map(|i| i as f32 - 7.5).collect();
        v.iter_mut().take(1).for_each(|x| *x = f32::MAX);
        v.iter_mut()
            .skip(1)
            .take(1)
            .for_each(|x| *x = -f32::MIN_POSITIVE / 2.0);
        assert!(all_finite(&v), "len {len}");
        for at in 0..len {
            for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
                let mut w = v.clone();
                w[at] = bad;
                assert!(!all_finite(&w), "len {len}, {bad} at {at}");
            }
        }
    }
}
