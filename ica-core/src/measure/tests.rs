use super::*;
use crate::model::tests::{labels, report};

/// A little LCG: the test's numbers without a dependency.
fn numbers(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }
}

/// 5 markers, 3 components, a random mixing and mean.
fn model() -> IcaModel {
    let mut r = numbers(7);
    let mixing = DMatrix::from_fn(15, 3, |_, _| r());
    let mean = (0..15).map(|_| 100.0 * r()).collect();
    IcaModel::new(labels(5), 120.0, mean, mixing, report(15, 3)).expect("valid parts")
}

/// `(x − mean) − M W (x − mean)` of one frame, by matrix-vector products.
fn residual_of(model: &IcaModel, x: &[f64]) -> DVector<f64> {
    let centred = DVector::from_iterator(x.len(), x.iter().zip(model.mean()).map(|(x, m)| x - m));
    let u = model.unmixing() * &centred;
    centred - model.mixing() * u
}

#[test]
fn residuals_in_blocks_are_the_residuals_of_each_frame() {
    let model = model();
    let mut r = numbers(11);
    // More than two blocks, the last one partial.
    let frames: Vec<Vec<f32>> = (0..2 * RESIDUAL_BLOCK + 37)
        .map(|_| (0..15).map(|_| (100.0 * r()) as f32).collect())
        .collect();
    let mut sq = [0.0; 5];
    for x in &frames {
        let x: Vec<f64> = x.iter().map(|&v| f64::from(v)).collect();
        let res = residual_of(&model, &x);
        for (k, s) in sq.iter_mut().enumerate() {
            *s += (0..3).map(|a| res[3 * k + a].powi(2)).sum::<f64>();
        }
    }
    let got = residual_by_marker_of(&model, frames.iter().map(Vec::as_slice));
    // In two parts that add, as a caller splitting the frames between threads sums them.
    let (a, b) = frames.split_at(RESIDUAL_BLOCK + 5);
    let mut parts = ResidualSums::of(&model, a.iter().map(Vec::as_slice));
    parts.add(&ResidualSums::of(&model, b.iter().map(Vec::as_slice)));
    for (k, (x, y)) in got.iter().zip(parts.rms()).enumerate() {
        assert!(
            (x - y).abs() <= 1e-12 * x,
            "marker {k}: {x} vs {y} in parts"
        );
    }
    for (k, s) in sq.iter().enumerate() {
        let want = (s / frames.len() as f64).sqrt();
        assert!(want > 1.0, "the residual is not trivial");
        assert!(
            (got[k] - want).abs() <= 1e-9 * want,
            "marker {k}: {} vs {want}",
            got[k]
        );
    }
}

#[test]
fn the_whitening_measures_the_residual_of_any_model_fitted_through_it() {
    use crate::fit::FitData;
    use crate::whiten::{Components, Moments};
    let mut r = numbers(5);
    // 5 markers; channel 4 never moves while training (a dead channel).
    let frame = |r: &mut dyn FnMut() -> f64, dead: f32| -> Vec<f32> {
        (0..15)
            .map(|c| if c == 4 { dead } else { (100.0 * r()) as f32 })
            .collect()
    };
    let training: Vec<f32> = (0..600).flat_map(|_| frame(&mut r, 12.5)).collect();
    let mut moments = Moments::new(15);
    moments
        .add_chunk(&FitData::new(&training, 15).expect("15 channels"))
        .expect("finite");
    let w = Whitener::from_moments(&moments, Components::Fixed(3)).expect("a whitening");
    assert_eq!(w.dead_channels, vec![4]);
    // A model through it, as FastICA makes one: M = E Λ^½ Rᵀ on the live rows.
    let rotation = nalgebra::Rotation3::from_euler_angles(0.3, -1.1, 2.0);
    let rotation = DMatrix::from_fn(3, 3, |i, j| rotation[(i, j)]);
    let scaled = DMatrix::from_fn(14, 3, |i, j| w.basis[(i, j)] * w.eigenvalues[j].sqrt());
    let live = scaled * rotation.transpose();
    let mut mixing = DMatrix::zeros(15, 3);
    for (row, &c) in w.live_channels.iter().enumerate() {
        mixing.row_mut(c).copy_from(&live.row(row));
    }
    let model = IcaModel::new(labels(5), 120.0, w.mean.clone(), mixing, report(15, 3))
        .expect("valid parts");
    // Other frames, the dead channel moving too.
    let frames: Vec<Vec<f32>> = (0..700)
        .map(|i| frame(&mut r, 12.5 + (i % 7) as f32))
        .collect();
    let by_model = residual_by_marker_of(&model, frames.iter().map(Vec::as_slice));
    let by_whitening = ResidualSums::of(&w, frames.iter().map(Vec::as_slice)).rms();
    for (k, (a, b)) in by_model.iter().zip(&by_whitening).enumerate() {
        assert!(*a > 1.0, "marker {k}: the residual is not trivial");
        assert!((a - b).abs() <= 1e-9 * a, "marker {k}: {a} vs {b}");
    }
    let means: Vec<Vec<f64>> = frames
        .chunks(50)
        .map(|block| {
            (0..15)
                .map(|c| block.iter().map(|f| f64::from(f[c])).sum::<f64>() / 50.0)
                .collect()
        })
        .collect();
    let (a, at_a) = slow_residual_of_means(&model, &means).expect("14 blocks");
    let (b, at_b) = slow_residual_of_means(&w, &means).expect("14 blocks");
    assert_eq!(at_a, at_b);
    assert!((a - b).abs() <= 1e-9 * a, "slow residual {a} vs {b}");
}

#[test]
fn the_slow_residual_is_the_leading_direction_of_the_block_residuals() {
    let model = model();
    let mut r = numbers(3);
    // Block means along one slow direction plus a little noise.
    let slow: Vec<f64> = (0..15)
        .map(|i| if i / 3 == 2 { 1.0 } else { 0.1 })
        .collect();
    let means: Vec<Vec<f64>> = (0..40)
        .map(|_| {
            let a = 10.0 * r();
            slow.iter()
                .zip(model.mean())
                .map(|(s, m)| m + a * s + 0.01 * r())
                .collect()
        })
        .collect();
    // Reference: the residuals' covariance and its largest eigenpair.
    let res: Vec<DVector<f64>> = means.iter().map(|x| residual_of(&model, x)).collect();
    let mean = res.iter().fold(DVector::zeros(15), |a, b| a + b) / res.len() as f64;
    let mut cov = DMatrix::zeros(15, 15);
    for x in &res {
        let d = x - &mean;
        cov += &d * d.transpose();
    }
    cov /= res.len() as f64;
    let eig = cov.symmetric_eigen();
    let top = eig.eigenvalues.imax();
    let v = eig.eigenvectors.column(top);
    let (marker, peak) = (0..5)
        .map(|k| (k, (0..3).map(|a| v[3 * k + a].powi(2)).sum::<f64>().sqrt()))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .expect("markers");
    let want = eig.eigenvalues[top].sqrt() * peak;
    let (got, at) = slow_residual_of_means(&model, &means).expect("enough blocks");
    assert_eq!(at, marker);
    assert!(want > 0.1, "the slow residual is not trivial: {want}");
    assert!((got - want).abs() <= 1e-6 * want, "{got} vs {want}");
    assert!(slow_residual_of_means(&model, &means[..7]).is_none());
}
