use proptest::prelude::*;

use super::push_f32;

fn both(value: f32) -> (String, String) {
    let mut ours = String::new();
    push_f32(&mut ours, value);
    (ours, format!("{value}"))
}

#[test]
fn edge_values_are_written_as_std_writes_them() {
    let edges = [
        0.0,
        -0.0,
        1.0,
        -1.0,
        0.1,
        0.3,
        1200.0,
        100.5,
        123_456_790.0,
        1.5e-7,
        1e-10,
        1e10,
        3.4e38,
        f32::MAX,
        f32::MIN,
        f32::MIN_POSITIVE,
        f32::from_bits(1),
        f32::EPSILON,
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        16_777_216.0,
        0.000_123_4,
    ];
    for value in edges {
        let (ours, std) = both(value);
        assert_eq!(ours, std, "bits {:#010x}", value.to_bits());
    }
}

#[test]
fn appends_to_what_is_there() {
    let mut out = String::from("a,");
    push_f32(&mut out, -2.5);
    assert_eq!(out, "a,-2.5");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(20_000))]

    #[test]
    fn any_bit_pattern_is_written_as_std_writes_it(bits in any::<u32>()) {
        let (ours, std) = both(f32::from_bits(bits));
        prop_assert_eq!(ours, std);
    }

    #[test]
    fn marker_scale_values_are_written_as_std_writes_them(value in -5000.0f32..5000.0) {
        let (ours, std) = both(value);
        prop_assert_eq!(ours, std);
    }
}
