use super::*;
use crate::fit::mixture;

#[test]
fn gaps_are_filled_close_to_the_hidden_values() {
    let mix = mixture::face_like(3000, 30, 4, 0.05, 3);
    let channels = mix.channels;
    let truth = mix.samples.clone();
    let mut samples = truth.clone();
    let mut missing = vec![false; truth.len()];
    // A marker (3 channels) gone for a block of 400 frames, and one frame mostly gone.
    for f in 1000..1400 {
        for c in 6..9 {
            missing[f * channels + c] = true;
            samples[f * channels + c] = f32::NAN;
        }
    }
    for c in 0..20 {
        missing[2000 * channels + c] = true;
    }
    let (after, report) =
        fill_gaps(&mut samples, &missing, channels, Components::Fixed(4)).expect("fills");
    assert_eq!(report.frames, 400);
    assert_eq!(report.samples, 1200);
    assert_eq!(report.frames_left_out, 1);
    assert!(after[2000 * channels]);
    assert!(!after[1000 * channels + 6]);
    let spread = (0..3000)
        .map(|f| f64::from(truth[f * channels + 7]).powi(2))
        .sum::<f64>()
        / 3000.0;
    let err = (1000..1400)
        .map(|f| f64::from(samples[f * channels + 7] - truth[f * channels + 7]).powi(2))
        .sum::<f64>()
        / 400.0;
    assert!(err < 0.01 * spread, "error {err} vs spread {spread}");
}
