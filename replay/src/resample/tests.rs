use crate::Take;

#[test]
fn resampling_interpolates_and_keeps_gaps() {
    let mut take = Take::new(vec!["a".into()], 60.0, 1);
    for f in 0..61 {
        take.push_frame(&[f as f32, 0.0, 0.0], &[f == 30]);
    }
    let up = take.resampled(120.0);
    assert_eq!(up.n_frames(), 121);
    assert_eq!(up.sample(3, 0), Some([1.5, 0.0, 0.0]));
    assert_eq!(up.sample(120, 0), Some([60.0, 0.0, 0.0]));
    // 29.5 and 30.5 touch the missing frame 30; 30 is it.
    assert!(up.is_missing(59, 0) && up.is_missing(60, 0) && up.is_missing(61, 0));
    assert!(!up.is_missing(58, 0) && !up.is_missing(62, 0));
    let down = take.resampled(30.0);
    assert_eq!(down.n_frames(), 31);
    assert_eq!(down.sample(1, 0), Some([2.0, 0.0, 0.0]));
    assert!(down.is_missing(15, 0));
}
