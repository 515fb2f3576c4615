//! Missing markers: least squares on the observed rows, conditioning flags, holding.

use ica_core::{FrameEdit, IcaModel, Projector, TrainReport};
use nalgebra::{DMatrix, DVector};
use rand::seq::index::sample;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

const MARKERS: usize = 109;
const N: usize = MARKERS * 3;
const M: usize = 20;
/// The "mouth": 12 contiguous markers.
const MOUTH: std::ops::Range<usize> = 60..72;
/// The component that lives on the mouth.
const SPEECH: usize = 3;

fn normal(rng: &mut ChaCha8Rng) -> f64 {
    StandardNormal.sample(rng)
}

fn report() -> TrainReport {
    TrainReport::untrained(N, M)
}

/// Random gaussian mixing (entries ~1 mm), except the speech component, which moves the
/// mouth markers and leaks only 0.1% elsewhere.
fn face_model(rng: &mut ChaCha8Rng) -> IcaModel {
    let mouth_rows = MOUTH.start * 3..MOUTH.end * 3;
    let mixing = DMatrix::from_fn(N, M, |j, k| {
        let v = normal(rng);
        if k == SPEECH && !mouth_rows.contains(&j) {
            1e-3 * v
        } else {
            v
        }
    });
    let labels = (0..MARKERS).map(|i| format!("m{i:03}")).collect();
    let mean = (0..N).map(|_| 1000.0 + 50.0 * normal(rng)).collect();
    IcaModel::new(labels, 120.0, mean, mixing, report()).expect("full rank")
}

/// `mean + M u + noise` in f32, and the noise.
fn frame(
    model: &IcaModel,
    u: &DVector<f64>,
    noise_mm: f64,
    rng: &mut ChaCha8Rng,
) -> (Vec<f32>, DVector<f64>) {
    let noise = DVector::from_fn(N, |_, _| noise_mm * normal(rng));
    let x = DVector::from_column_slice(model.mean()) + model.mixing() * u + &noise;
    (x.iter().map(|&v| v as f32).collect(), noise)
}

fn observed_rows(mask: &[bool]) -> Vec<usize> {
    (0..N).filter(|j| !mask[j / 3]).collect()
}

/// `1 / σ_min` of the mixing rows in `rows`: how much noise on those rows can move `u`.
fn inv_smallest_singular(model: &IcaModel, rows: &[usize]) -> f64 {
    let sub = model.mixing().select_rows(rows);
    1.0 / sub.singular_values().min()
}

#[test]
fn twenty_percent_hidden_stays_near_the_full_frame_solution() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let model = face_model(&mut rng);
    let mut p = Projector::new(&model);
    let (mut u_full, mut u_masked) = (vec![0.0_f32; M], vec![0.0_f32; M]);
    let noise_mm = 0.05;
    for _ in 0..30 {
        let u_true = DVector::from_fn(M, |_, _| 3.0 * normal(&mut rng));
        let (x, noise) = frame(&model, &u_true, noise_mm, &mut rng);
        let mut mask = vec![false; MARKERS];
        // Hide 20% of the markers, but not the mouth: the speech component must stay observable.
        let candidates: Vec<usize> = (0..MARKERS).filter(|i| !MOUTH.contains(i)).collect();
        for i in sample(&mut rng, candidates.len(), MARKERS / 5) {
            mask[candidates[i]] = true;
        }
        p.project_into(&x, &mut u_full).expect("sizes");
        let status = p
            .project_masked_into(&x, Some(&mask), &mut u_masked)
            .expect("sizes");
        assert!(status.masked && !status.ill_conditioned && !status.held);
        assert_eq!(status.missing_markers, MARKERS / 5);
        // Both estimates are u_true plus a pseudo-inverse of the noise:
        // |u_masked - u_full| <= |noise_o| / σ_min(M_o) + |noise| / σ_min(M).
        let obs = observed_rows(&mask);
        let noise_o = noise.select_rows(&obs).norm();
        let bound = noise_o * inv_smallest_singular(&model, &obs)
            + noise.norm() * inv_smallest_singular(&model, &(0..N).collect::<Vec<_>>());
        // f32: ~1e-4 per component (see the full-frame test), kept separate from the bound.
        let slack = 1e-3;
        let diff = u_masked
            .iter()
            .zip(&u_full)
            .map(|(a, b)| f64::from(a - b).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(
            diff <= bound + slack,
            "masked differs by {diff}, bound {bound}"
        );
        // The bound itself is small next to |u| ~ 13: the test says something.
        assert!(bound < 0.5, "bound {bound}");
    }
}

#[test]
fn whole_mouth_hidden_is_flagged_and_holds_the_speech_component() {
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let model = face_model(&mut rng);
    let mut p = Projector::new(&model);
    let edit = FrameEdit::identity(M);
    let (mut u, mut out) = (vec![0.0_f32; M], vec![0.0_f32; N]);
    // A full frame first: the prior the occluded frame falls back on.
    let u_prev = DVector::from_fn(M, |_, _| 3.0 * normal(&mut rng));
    let (x_prev, _) = frame(&model, &u_prev, 0.0, &mut rng);
    p.process_into(&x_prev, None, &edit, &mut out, &mut u)
        .expect("sizes");
    let prior = u.clone();

    let mut u_true = u_prev.clone();
    u_true[SPEECH] += 4.0;
    u_true[0] -= 2.0;
    let (x, _) = frame(&model, &u_true, 0.0, &mut rng);
    let mut mask = vec![false; MARKERS];
    mask[MOUTH].fill(true);
    let status = p
        .process_into(&x, Some(&mask), &edit, &mut out, &mut u)
        .expect("sizes");
    assert!(
        status.masked && status.ill_conditioned && !status.held,
        "{status:?}"
    );
    assert!(status.observability < 1e-3, "{status:?}");
    assert!(out.iter().all(|v| v.is_finite()) && u.iter().all(|v| v.is_finite()));
    // The unobservable component stays at its last value instead of exploding...
    assert!(
        (u[SPEECH] - prior[SPEECH]).abs() < 0.05,
        "speech {} vs prior {}",
        u[SPEECH],
        prior[SPEECH]
    );
    // ...while the visible ones follow the data, up to the ridge's 1% pull toward the prior.
    for k in (0..M).filter(|&k| k != SPEECH) {
        let err = (f64::from(u[k]) - u_true[k]).abs();
        let moved = (u_true[k] - f64::from(prior[k])).abs();
        assert!(
            err <= 0.02 * moved + 0.02,
            "component {k}: off by {err}, moved {moved}"
        );
    }
}

/// A long occlusion with the model's own prior (a trained model's residual variance): each
/// ill-conditioned frame's solution becomes the next frame's prior, so a solve that moves the
/// unseen component off its prior compounds frame after frame. It must hold instead (on
/// Facial-Sing, hiding every face marker for ten frames had sent the output metres away).
#[test]
fn a_long_occlusion_holds_the_unseen_component_with_the_models_prior() {
    let mut rng = ChaCha8Rng::seed_from_u64(15);
    let base = face_model(&mut rng);
    // Discarded eigenvalues worth 0.05 mm² per channel: the prior's weight, as training sets it.
    let mut report = report();
    report.eigenvalues = [
        vec![100.0; M],
        vec![0.05 * N as f64 / (N - M) as f64; N - M],
    ]
    .concat();
    let model = IcaModel::new(
        base.labels().to_vec(),
        120.0,
        base.mean().to_vec(),
        base.mixing().clone(),
        report,
    )
    .expect("full rank");
    assert!((model.residual_variance() - 0.05).abs() < 1e-9);
    let mut p = Projector::new(&model);
    let edit = FrameEdit::identity(M);
    let (mut u, mut out) = (vec![0.0_f32; M], vec![0.0_f32; N]);
    let u_prev = DVector::from_fn(M, |_, _| 3.0 * normal(&mut rng));
    let (x_prev, _) = frame(&model, &u_prev, 0.0, &mut rng);
    p.process_into(&x_prev, None, &edit, &mut out, &mut u)
        .expect("sizes");
    let prior = u[SPEECH];
    let mut mask = vec![false; MARKERS];
    mask[MOUTH].fill(true);
    for f in 0..300 {
        let mut u_true = u_prev.clone();
        u_true[0] += (f as f64 * 0.05).sin();
        let (x, _) = frame(&model, &u_true, 0.05, &mut rng);
        let status = p
            .process_into(&x, Some(&mask), &edit, &mut out, &mut u)
            .expect("sizes");
        assert!(
            (u[SPEECH] - prior).abs() < 0.05,
            "frame {f}: speech {} drifted from {prior}",
            u[SPEECH]
        );
        assert!(
            (f64::from(u[0]) - u_true[0]).abs() < 0.05,
            "frame {f}: a visible component stopped following the data"
        );
        // Measured on the data alone: the prior does not make the mouth observable.
        assert!(
            status.ill_conditioned && status.observability < 1e-3,
            "frame {f}: {status:?}"
        );
    }
}

#[test]
fn fewer_observed_channels_than_components_holds() {
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    let model = face_model(&mut rng);
    let mut p = Projector::new(&model);
    let edit = FrameEdit::identity(M);
    let (mut u, mut out) = (vec![0.0_f32; M], vec![0.0_f32; N]);
    // 6 markers = 18 channels < 20 components.
    let mut mask = vec![true; MARKERS];
    mask[..6].fill(false);
    let (x, _) = frame(
        &model,
        &DVector::from_fn(M, |_, _| normal(&mut rng)),
        0.0,
        &mut rng,
    );

    // No good frame yet: the mean pose.
    let status = p
        .process_into(&x, Some(&mask), &edit, &mut out, &mut u)
        .expect("sizes");
    assert!(status.held && status.masked && status.observability == 0.0);
    assert!(u.iter().all(|&v| v == 0.0));
    assert!(out
        .iter()
        .zip(model.mean())
        .all(|(o, m)| (f64::from(*o) - m).abs() < 1e-3));

    // After a good frame: that frame's components.
    let (x_good, _) = frame(
        &model,
        &DVector::from_fn(M, |_, _| normal(&mut rng)),
        0.0,
        &mut rng,
    );
    let mut u_good = vec![0.0_f32; M];
    p.project_into(&x_good, &mut u_good).expect("sizes");
    let status = p
        .process_into(&x, Some(&mask), &edit, &mut out, &mut u)
        .expect("sizes");
    assert!(status.held);
    assert_eq!(u, u_good);

    // reset() forgets it.
    p.reset();
    p.process_into(&x, Some(&mask), &edit, &mut out, &mut u)
        .expect("sizes");
    assert!(u.iter().all(|&v| v == 0.0));
}

#[test]
fn mostly_hidden_frame_uses_the_direct_gram_and_agrees() {
    // 70% hidden takes the sum-over-observed branch instead of the downdate.
    let mut rng = ChaCha8Rng::seed_from_u64(14);
    let model = face_model(&mut rng);
    let mut p = Projector::new(&model);
    let u_true = DVector::from_fn(M, |_, _| 3.0 * normal(&mut rng));
    let (x, _) = frame(&model, &u_true, 0.0, &mut rng);
    let mut mask = vec![true; MARKERS];
    for i in (0..MARKERS).step_by(3) {
        mask[i] = false;
    }
    for i in MOUTH {
        mask[i] = false;
    }
    let mut u = vec![0.0_f32; M];
    let status = p
        .project_masked_into(&x, Some(&mask), &mut u)
        .expect("sizes");
    assert!(status.masked && !status.ill_conditioned, "{status:?}");
    let err = u
        .iter()
        .zip(u_true.iter())
        .map(|(a, b)| (f64::from(*a) - b).abs())
        .fold(0.0, f64::max);
    assert!(err < 2e-3, "noise-free frame recovered to {err}");
}
