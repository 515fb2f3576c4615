use super::*;

#[test]
fn thinned_keeps_a_short_stream_whole_and_a_long_one_within_its_limit() {
    let mut short = Thinned::new(100);
    (0..100).for_each(|v| short.push(f64::from(v)));
    assert_eq!(short.values.len(), 100);
    let mut long = Thinned::new(100);
    (0..1_000_000).for_each(|v| long.push(f64::from(v)));
    assert!(
        (50..=100).contains(&long.values.len()),
        "{}",
        long.values.len()
    );
    // Evenly spread: every kept value is a multiple of the final stride.
    assert!(long.values.iter().all(|v| *v as usize % long.stride == 0));
    assert!(*long.values.last().expect("kept") > 900_000.0);
}
