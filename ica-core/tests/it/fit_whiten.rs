//! Whitening and input handling: component count, rank, dead channels, missing frames, errors.

use ica_core::fit::{mixture, FastIcaParams, FitData, FitError};
use ica_core::whiten::{whiten, Components};
use nalgebra::DMatrix;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// `frames x channels` data whose covariance has exactly the eigenvalues `variances` along
/// random orthonormal axes (uniform, hence non-Gaussian, scores made exactly white).
fn known_spectrum(frames: usize, channels: usize, variances: &[f64], seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let k = variances.len();
    let raw = DMatrix::from_fn(channels, k, |_, _| rng.random_range(-1.0..1.0));
    let axes = raw.qr().q();
    let mut scores = DMatrix::from_fn(frames, k, |_, _| rng.random_range(-1.0..1.0));
    for mut col in scores.column_iter_mut() {
        let mean = col.mean();
        col.add_scalar_mut(-mean);
    }
    // Exactly white scores (unbiased covariance = I), so the spectrum is exactly `variances`.
    let cov = scores.transpose() * &scores / (frames as f64 - 1.0);
    let chol = cov.cholesky().expect("scores have full rank");
    let l_inv = chol
        .l()
        .try_inverse()
        .expect("triangular factor is invertible");
    let white = scores * l_inv.transpose();
    let mut x = Vec::with_capacity(frames * channels);
    for f in 0..frames {
        for c in 0..channels {
            let v: f64 = (0..k)
                .map(|j| axes[(c, j)] * variances[j].sqrt() * white[(f, j)])
                .sum();
            x.push(10.0 + v);
        }
    }
    x
}

#[test]
fn variance_target_picks_the_smallest_m_reaching_it() {
    // Shares of the total: 0.5, 0.3, 0.15, 0.04, 0.01 -> cumulative 0.5, 0.8, 0.95, 0.99, 1.0.
    let variances = [50.0, 30.0, 15.0, 4.0, 1.0];
    let x = known_spectrum(2000, 12, &variances, 1);
    let data = FitData::new(&x, 12).expect("whole frames");
    for (target, m) in [(0.90, 3), (0.95, 3), (0.97, 4), (0.99, 4), (0.995, 5)] {
        let w = whiten(&data, Components::VarianceTarget(target)).expect("whitens");
        assert_eq!(w.components(), m, "target {target}");
        assert_eq!(w.rank, 5);
        for (got, want) in w.eigenvalues.iter().zip(variances) {
            assert!(
                (got - want).abs() < 1e-9 * want,
                "eigenvalue {got} vs {want}"
            );
        }
        let z_cov = &w.whitened * w.whitened.transpose() / (2000.0 - 1.0);
        assert!((z_cov - DMatrix::identity(m, m)).amax() < 1e-9);
    }
}

#[test]
fn variance_target_outside_range_is_a_typed_error() {
    let x = known_spectrum(100, 6, &[3.0, 2.0, 1.0], 2);
    let data = FitData::new(&x, 6).expect("whole frames");
    for target in [0.5, 0.89, 0.9995, 1.0, f64::NAN] {
        let err = FastIcaParams::default()
            .variance_target(target)
            .fit(&data)
            .expect_err("bad target");
        assert!(
            matches!(err, FitError::VarianceTarget { .. }),
            "{target}: {err}"
        );
    }
}

#[test]
fn fixed_m_above_rank_or_zero_is_a_clear_error() {
    let x = known_spectrum(500, 10, &[5.0, 3.0, 2.0, 1.0], 3);
    let data = FitData::new(&x, 10).expect("whole frames");
    let err = FastIcaParams::default()
        .n_components(6)
        .fit(&data)
        .expect_err("rank 4");
    assert_eq!(err, FitError::ComponentsExceedRank { m: 6, rank: 4 });
    assert_eq!(err.to_string(), "m = 6 is larger than the data's rank (4)");
    let err = FastIcaParams::default()
        .n_components(0)
        .fit(&data)
        .expect_err("m = 0");
    assert_eq!(err, FitError::ZeroComponents);
    assert!(FastIcaParams::default().n_components(4).fit(&data).is_ok());
}

#[test]
fn dead_channels_are_reported_and_never_produce_nan() {
    let mix = mixture::face_like(3000, 30, 4, 0.2, 5);
    let mut x = mix.samples.clone();
    let mut missing = vec![false; x.len()];
    for f in 0..3000 {
        x[f * 30 + 7] = 123.5; // a constant (stuck) marker coordinate
        x[f * 30 + 20] = f32::NAN; // a channel never observed
        missing[f * 30 + 20] = true;
    }
    let data = FitData::new(&x, 30)
        .and_then(|d| d.with_missing(&missing))
        .expect("shapes match");
    let out = FastIcaParams::default()
        .n_components(4)
        .fit(&data)
        .expect("fits");
    assert_eq!(out.report.dead_channels, vec![7, 20]);
    assert_eq!(
        out.report.frames_used, 3000,
        "an always-missing channel excludes no frame"
    );
    assert!((out.mean[7] - 123.5).abs() < 1e-9);
    assert_eq!(out.mean[20], 0.0);
    for dead in [7, 20] {
        assert!(out.mixing.row(dead).iter().all(|&v| v == 0.0));
        assert!(out.unmixing.column(dead).iter().all(|&v| v == 0.0));
    }
    let all_finite = |m: &DMatrix<f64>| m.iter().all(|v| v.is_finite());
    assert!(all_finite(&out.mixing) && all_finite(&out.unmixing));
    assert!(all_finite(out.sources.as_ref().expect("kept")));
    assert!(out.mean.iter().all(|v| v.is_finite()));
}

#[test]
fn frames_with_missing_samples_are_excluded_and_counted() {
    let mix = mixture::face_like(3000, 30, 4, 0.2, 6);
    let mut x = mix.samples.clone();
    let mut missing = vec![false; x.len()];
    let dropped: Vec<usize> = (0..3000).filter(|f| f % 10 == 3).collect();
    for &f in &dropped {
        // An occluded marker: its three channels, with garbage values that must not be read.
        for c in 9..12 {
            missing[f * 30 + c] = true;
            x[f * 30 + c] = if f % 20 == 3 { f32::NAN } else { 1e30 };
        }
    }
    let data = FitData::new(&x, 30)
        .and_then(|d| d.with_missing(&missing))
        .expect("shapes match");
    let out = FastIcaParams::default()
        .n_components(4)
        .fit(&data)
        .expect("fits");
    assert_eq!(out.report.frames_total, 3000);
    assert_eq!(out.report.frames_used, 3000 - dropped.len());
    assert!(out.used_frames.iter().all(|f| f % 10 != 3));
    assert_eq!(
        out.sources.as_ref().expect("kept").nrows(),
        out.used_frames.len()
    );
    // The statistics are those of the complete frames alone.
    let complete: Vec<f32> = (0..3000)
        .filter(|f| f % 10 != 3)
        .flat_map(|f| x[f * 30..(f + 1) * 30].to_vec())
        .collect();
    let reference = FastIcaParams::default()
        .n_components(4)
        .fit(&FitData::new(&complete, 30).expect("whole frames"))
        .expect("fits");
    assert_eq!(out.mean, reference.mean);
    assert_eq!(out.report.eigenvalues, reference.report.eigenvalues);
}

#[test]
fn non_finite_present_samples_and_bad_shapes_are_typed_errors() {
    let mut x = vec![1.0f32; 40 * 4];
    x[17 * 4 + 2] = f32::INFINITY;
    let err = FastIcaParams::default()
        .fit(&FitData::new(&x, 4).expect("whole frames"))
        .expect_err("infinite sample");
    assert!(
        matches!(
            err,
            FitError::NonFinite {
                frame: 17,
                channel: 2,
                ..
            }
        ),
        "{err}"
    );
    assert_eq!(
        FitData::new(&x[..10], 4).expect_err("ragged"),
        FitError::RaggedSamples {
            len: 10,
            channels: 4
        }
    );
    assert_eq!(
        FitData::new(&x, 0).expect_err("no channels"),
        FitError::NoChannels
    );
    let mask = vec![false; 3];
    let err = FitData::new(&x, 4).and_then(|d| d.with_missing(&mask));
    assert_eq!(
        err.expect_err("mask"),
        FitError::MaskLength {
            expected: 160,
            got: 3
        }
    );
}

#[test]
fn too_few_complete_frames_or_no_variance_are_typed_errors() {
    let x = known_spectrum(50, 6, &[3.0, 2.0, 1.0], 4);
    let mut missing = vec![false; x.len()];
    for f in 0..47 {
        missing[f * 6] = true;
    }
    let data = FitData::new(&x, 6)
        .and_then(|d| d.with_missing(&missing))
        .expect("shapes");
    let err = FastIcaParams::default()
        .n_components(3)
        .fit(&data)
        .expect_err("3 frames");
    assert_eq!(
        err,
        FitError::TooFewFrames {
            used: 3,
            total: 50,
            needed: 4
        }
    );
    let flat = vec![2.0f64; 60];
    let err = FastIcaParams::default()
        .fit(&FitData::new(&flat, 6).expect("whole frames"))
        .expect_err("constant data");
    assert_eq!(err, FitError::NoVariance { channels: 6 });
}

#[test]
fn bad_iteration_parameters_are_typed_errors() {
    let x = known_spectrum(200, 6, &[3.0, 2.0, 1.0], 5);
    let data = FitData::new(&x, 6).expect("whole frames");
    let base = FastIcaParams::default().n_components(3);
    assert_eq!(
        base.clone().tol(0.0).fit(&data).expect_err("tol"),
        FitError::Tolerance { tol: 0.0 }
    );
    assert_eq!(
        base.clone().max_iter(0).fit(&data).expect_err("iters"),
        FitError::ZeroIterations
    );
    assert_eq!(
        base.restarts(0).fit(&data).expect_err("restarts"),
        FitError::ZeroRestarts
    );
}
