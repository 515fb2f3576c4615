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

#[test]
fn a_fill_is_the_posterior_mean_given_the_visible_channels() {
    // 12 channels (the last dead), 3 kept axes of 5: the fill from the model's whole-frame
    // system less the missing channels must be the one from the visible channels alone.
    let (channels, m) = (12, 3);
    let live: Vec<usize> = (0..11).collect();
    let basis = DMatrix::from_fn(11, m, |r, k| ((r * 7 + k * 3) % 5) as f64 * 0.3 - 0.55);
    let eigenvalues = [4.0, 2.0, 1.0, 0.5, 0.25];
    let mean: Vec<f64> = (0..channels).map(|c| c as f64 * 0.5).collect();
    let model = GapModel::from_parts(&mean, &live, &basis, &eigenvalues, channels);
    let mut frame: Vec<f32> = (0..channels)
        .map(|c| (c as f32 * 1.3).sin() * 2.0)
        .collect();
    let missing: Vec<bool> = (0..channels).map(|c| [2, 5, 11].contains(&c)).collect();
    // What the kept axes leave out, per live channel.
    let (a, sigma2) = (&model.loadings, (0.5 + 0.25) / 11.0);
    let mut gram = DMatrix::<f64>::identity(m, m) * sigma2;
    let mut rhs = DVector::<f64>::zeros(m);
    for c in (0..channels).filter(|&c| !missing[c]) {
        let row = DVector::from_column_slice(&a[c * m..(c + 1) * m]);
        gram += &row * row.transpose();
        rhs += &row * (f64::from(frame[c]) - mean[c]);
    }
    let v = gram.cholesky().expect("positive definite").solve(&rhs);
    let expected: Vec<f64> = (0..channels)
        .map(|c| mean[c] + (0..m).map(|k| a[c * m + k] * v[k]).sum::<f64>())
        .collect();
    let before = frame.clone();
    model.fill(&mut frame, &missing);
    for c in 0..channels {
        let want = if missing[c] {
            expected[c]
        } else {
            f64::from(before[c])
        };
        assert!(
            (f64::from(frame[c]) - want).abs() < 1e-5,
            "channel {c}: {} against {want}",
            frame[c]
        );
    }
}

#[test]
fn a_filler_fills_each_frame_as_a_fresh_one_would() {
    // Frames whose gaps change, come back and vanish: the filler keeps a factor only while the
    // missing set stays the same, so every fill is bit for bit the one-frame fill.
    let (channels, m) = (9, 2);
    let live: Vec<usize> = (0..channels).collect();
    let basis = DMatrix::from_fn(channels, m, |r, k| ((r * 5 + k * 2) % 7) as f64 * 0.2 - 0.6);
    let eigenvalues = [3.0, 1.5, 0.4, 0.2];
    let mean: Vec<f64> = (0..channels).map(|c| c as f64 * 0.25).collect();
    let model = GapModel::from_parts(&mean, &live, &basis, &eigenvalues, channels);
    let gaps: [&[usize]; 6] = [&[1], &[1], &[1, 4], &[], &[1], &[7, 8]];
    let mut filler = model.filler();
    for (f, gone) in gaps.iter().enumerate() {
        let missing: Vec<bool> = (0..channels).map(|c| gone.contains(&c)).collect();
        let frame: Vec<f32> = (0..channels)
            .map(|c| ((c + 3 * f) as f32 * 0.7).cos())
            .collect();
        let (mut alone, mut kept) = (frame.clone(), frame.clone());
        model.fill(&mut alone, &missing);
        filler.fill(&mut kept, &missing);
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&kept), bits(&alone), "frame {f}");
        for c in 0..channels {
            assert_eq!(kept[c] != frame[c], missing[c], "frame {f}, channel {c}");
        }
    }
}
