//! The per-frame projector against the f64 model: full frames, edits, missing markers.

use ica_core::edit::copy_add_into;
use ica_core::{FrameEdit, FrameError, IcaModel, Projector, TrainReport};
use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

const MARKERS: usize = 109;
const N: usize = MARKERS * 3;
const M: usize = 20;

fn report(channels: usize, components: usize) -> TrainReport {
    TrainReport::untrained(channels, components)
}

fn normal(rng: &mut ChaCha8Rng) -> f64 {
    StandardNormal.sample(rng)
}

/// A face-sized model: mean ~ a metre from the origin in millimetres, mixing entries ~1 mm.
fn model_from(mixing: DMatrix<f64>, rng: &mut ChaCha8Rng) -> IcaModel {
    let (n, m) = mixing.shape();
    let labels = (0..n / 3).map(|i| format!("m{i:03}")).collect();
    let mean = (0..n).map(|_| 1000.0 + 50.0 * normal(rng)).collect();
    IcaModel::new(labels, 120.0, mean, mixing, report(n, m))
        .expect("random gaussian mixing has full rank")
}

fn random_model(seed: u64) -> (IcaModel, ChaCha8Rng) {
    random_model_m(seed, M)
}

fn random_model_m(seed: u64, m: usize) -> (IcaModel, ChaCha8Rng) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mixing = DMatrix::from_fn(N, m, |_, _| normal(&mut rng));
    (model_from(mixing, &mut rng), rng)
}

/// A frame `mean + M u + noise` in f64, and its f32 copy.
fn frame(
    model: &IcaModel,
    u: &DVector<f64>,
    noise_mm: f64,
    rng: &mut ChaCha8Rng,
) -> (DVector<f64>, Vec<f32>) {
    let mean = DVector::from_column_slice(model.mean());
    let noise = DVector::from_fn(model.channels(), |_, _| noise_mm * normal(rng));
    let x = mean + model.mixing() * u + noise;
    let x32 = x.iter().map(|&v| v as f32).collect();
    (x, x32)
}

fn random_u(rng: &mut ChaCha8Rng, m: usize) -> DVector<f64> {
    DVector::from_fn(m, |_, _| 3.0 * normal(rng))
}

fn max_abs_diff(a: &[f32], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (f64::from(*x) - y).abs())
        .fold(0.0, f64::max)
}

#[test]
fn full_frame_matches_the_f64_model_to_f32_precision() {
    // Every kernel: paired narrow panels (m <= 8), wide panels (m <= 32), rows (m > 32),
    // and remainders of the four-column resynthesis.
    for m in [1, 3, 6, 10, 20, 33] {
        let (model, mut rng) = random_model_m(u64::try_from(m).expect("small"), m);
        let mut p = Projector::new(&model);
        let (mut u, mut out) = (vec![0.0_f32; m], vec![0.0_f32; N]);
        for _ in 0..5 {
            let (x, x32) = frame(&model, &random_u(&mut rng, m), 0.5, &mut rng);
            p.project_into(&x32, &mut u).expect("sizes match");
            let want = model.unmixing() * (&x - DVector::from_column_slice(model.mean()));
            // |u| ~ 3, W entries ~ 1/18: f32 rounding of x (6e-5 mm) and of the sums < 1e-4.
            let err = max_abs_diff(&u, want.as_slice());
            assert!(err < 1e-4, "m = {m}: u off by {err}");
            p.resynth_into(&u, &mut out).expect("sizes match");
            let back = DVector::from_column_slice(model.mean()) + model.mixing() * &want;
            // Coordinates ~1000 mm: f32 spacing 6e-5 mm, plus M·(u error).
            let err = max_abs_diff(&out, back.as_slice());
            assert!(err < 5e-4, "m = {m}: x off by {err}");
        }
    }
}

#[test]
fn process_into_translates_one_component() {
    let (model, mut rng) = random_model(2);
    let mut p = Projector::new(&model);
    let (_, x32) = frame(&model, &random_u(&mut rng, M), 0.0, &mut rng);
    let (mut u0, mut x0) = (vec![0.0_f32; M], vec![0.0_f32; N]);
    let identity = FrameEdit::identity(M);
    let status = p
        .process_into(&x32, None, &identity, &mut x0, &mut u0)
        .expect("sizes match");
    assert!(!status.masked && !status.held && status.observability == 1.0);
    let mut edit = FrameEdit::identity(M);
    edit.set_offset(5, 2.5).expect("in range");
    let (mut u1, mut x1) = (vec![0.0_f32; M], vec![0.0_f32; N]);
    p.process_into(&x32, None, &edit, &mut x1, &mut u1)
        .expect("sizes match");
    assert!((u1[5] - u0[5] - 2.5).abs() < 1e-5);
    for j in 0..N {
        let want = 2.5 * model.mixing()[(j, 5)];
        assert!(
            (f64::from(x1[j] - x0[j]) - want).abs() < 5e-4,
            "channel {j}"
        );
    }
}

#[test]
fn copy_add_adds_a_component_of_another_model() {
    let (m1, mut rng) = random_model(3);
    let (m2, _) = random_model(4);
    let (p1, p2) = (Projector::new(&m1), Projector::new(&m2));
    let u1: Vec<f32> = (0..M).map(|_| rng.random_range(-2.0..2.0)).collect();
    let u2: Vec<f32> = (0..M).map(|_| rng.random_range(-2.0..2.0)).collect();
    let mut out = vec![0.0_f32; N];
    copy_add_into(&p1, &u1, &p2, &u2, 7, &mut out).expect("same channels");
    for (j, &got) in out.iter().enumerate() {
        let base: f64 = m1.mean()[j]
            + (0..M)
                .map(|k| m1.mixing()[(j, k)] * f64::from(u1[k]))
                .sum::<f64>();
        let want = base + m2.mixing()[(j, 7)] * f64::from(u2[7]);
        assert!((f64::from(got) - want).abs() < 5e-4);
    }
    assert!(matches!(
        copy_add_into(&p1, &u1, &p2, &u2, M, &mut out),
        Err(FrameError::ComponentOutOfRange { index: M, .. })
    ));
}

#[test]
fn wrong_buffer_lengths_are_errors_not_panics() {
    let (model, _) = random_model(5);
    let mut p = Projector::new(&model);
    let (mut u, mut out) = (vec![0.0_f32; M], vec![0.0_f32; N]);
    assert_eq!(
        p.project_into(&[0.0; 10], &mut u),
        Err(FrameError::Length {
            what: "frame",
            expected: N,
            got: 10
        })
    );
    assert_eq!(
        p.project_masked_into(&vec![0.0; N], Some(&[false; 3]), &mut u),
        Err(FrameError::Length {
            what: "missing mask",
            expected: MARKERS,
            got: 3
        })
    );
    let edit = FrameEdit::identity(M + 1);
    assert!(matches!(
        p.process_into(&vec![0.0; N], None, &edit, &mut out, &mut u),
        Err(FrameError::Length { what: "edit", .. })
    ));
    assert!(p.resynth_into(&u[..3], &mut out).is_err());
}

#[test]
fn nan_coordinates_count_as_missing() {
    let (model, mut rng) = random_model(6);
    let mut p = Projector::new(&model);
    let u_true = random_u(&mut rng, M);
    let (_, mut x32) = frame(&model, &u_true, 0.0, &mut rng);
    x32[3 * 40 + 1] = f32::NAN;
    let (mut u, mut out) = (vec![0.0_f32; M], vec![0.0_f32; N]);
    let status = p
        .process_into(&x32, None, &FrameEdit::identity(M), &mut out, &mut u)
        .expect("sizes");
    assert!(status.masked && !status.ill_conditioned && !status.held);
    assert_eq!(status.missing_markers, 1);
    assert!(max_abs_diff(&u, u_true.as_slice()) < 1e-3);
    let clean = DVector::from_column_slice(model.mean()) + model.mixing() * &u_true;
    // The NaN marker is filled in from the model.
    assert!(max_abs_diff(&out, clean.as_slice()) < 1e-2);
}
