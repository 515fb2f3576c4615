//! Recovery of known sources from face-like mixtures, and the output conventions.

use ica_core::fit::{amari_index, mixture, Algorithm, Contrast, FastIcaParams, FitData, FitOutput};
use nalgebra::DMatrix;

/// Pearson correlation of two equally long series.
fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma).powi(2);
        sbb += (y - mb).powi(2);
    }
    sab / (saa * sbb).sqrt()
}

/// For each true source, the largest |correlation| with any recovered component.
fn best_correlations(truth: &DMatrix<f64>, fit: &FitOutput) -> Vec<f64> {
    let est = fit.sources.as_ref().expect("sources kept by default");
    assert_eq!(est.nrows(), truth.nrows(), "no frame was excluded");
    truth
        .column_iter()
        .map(|t| {
            est.column_iter()
                .map(|e| correlation(t.as_slice(), e.as_slice()).abs())
                .fold(0.0, f64::max)
        })
        .collect()
}

fn fit_mixture(
    frames: usize,
    k: usize,
    seed: u64,
    params: FastIcaParams,
) -> (mixture::Mixture, FitOutput) {
    let mix = mixture::face_like(frames, 60, k, 0.2, seed);
    let data = FitData::new(&mix.samples, mix.channels).expect("whole frames");
    let out = params.n_components(k).fit(&data).expect("fit succeeds");
    (mix, out)
}

#[test]
fn recovers_known_sources_at_m6_and_m10_for_several_seeds() {
    for (k, frames) in [(6, 10_000), (10, 12_000)] {
        for seed in [1, 2, 3] {
            let (mix, out) = fit_mixture(frames, k, seed, FastIcaParams::default().seed(seed));
            let best = &out.report.restarts[out.report.best_restart];
            assert!(best.converged, "k={k} seed={seed}: {best:?}");
            let ai = amari_index(&(&out.unmixing * &mix.mixing)).expect("square, finite");
            assert!(ai < 0.08, "k={k} seed={seed}: amari index {ai}");
            for (i, c) in best_correlations(&mix.sources, &out).iter().enumerate() {
                assert!(*c > 0.95, "k={k} seed={seed}: source {i} best |corr| {c}");
            }
        }
    }
}

#[test]
fn unmixing_inverts_mixing_and_reconstructs_frames() {
    let (mix, out) = fit_mixture(3000, 6, 9, FastIcaParams::default());
    let identity = &out.unmixing * &out.mixing;
    assert!((identity - DMatrix::identity(6, 6)).amax() < 1e-9);
    // x ≈ mean + M u within the noise floor (0.2 mm RMS) for every frame.
    let u = out.sources.as_ref().expect("kept");
    let mut sq = 0.0;
    for f in 0..mix.frames {
        for c in 0..mix.channels {
            let x = f64::from(mix.samples[f * mix.channels + c]);
            let rec = out.mean[c] + out.mixing.row(c).dot(&u.row(f));
            sq += (x - rec).powi(2);
        }
    }
    let rms = (sq / (mix.frames * mix.channels) as f64).sqrt();
    assert!(rms < 0.25, "reconstruction rms {rms} mm");
}

#[test]
fn sign_and_order_convention_holds() {
    let (_, out) = fit_mixture(4000, 6, 4, FastIcaParams::default());
    let v = &out.component_variance;
    assert!(v.windows(2).all(|w| w[0] >= w[1]), "variance order {v:?}");
    for (i, col) in out.mixing.column_iter().enumerate() {
        assert!((col.norm_squared() - v[i]).abs() < 1e-9 * v[i]);
    }
    let u = out.sources.as_ref().expect("kept");
    let frames = u.nrows() as f64;
    let threshold = ica_core::fit::SKEW_SIGNIFICANT * (6.0 / frames).sqrt();
    for (i, col) in u.column_iter().enumerate() {
        let mean = col.mean();
        let var = col.iter().map(|y| (y - mean).powi(2)).sum::<f64>() / frames;
        let skew = col.iter().map(|y| (y - mean).powi(3)).sum::<f64>() / frames / var.powf(1.5);
        assert!((var - 1.0).abs() < 1e-3, "component {i} variance {var}");
        if skew.abs() >= threshold {
            assert!(skew > 0.0, "component {i} skewness {skew}");
        } else {
            let m = out.mixing.column(i);
            assert!(m[m.iamax()] > 0.0, "component {i} largest loading negative");
        }
    }
}

#[test]
fn same_seed_gives_identical_output_and_other_seeds_use_other_starts() {
    let params = FastIcaParams::default().seed(42).restarts(3);
    let (_, a) = fit_mixture(2000, 6, 5, params.clone());
    let (_, b) = fit_mixture(2000, 6, 5, params);
    assert_eq!(a.mixing, b.mixing);
    assert_eq!(a.unmixing, b.unmixing);
    assert_eq!(a.sources, b.sources);
    assert_eq!(a.report, b.report);
    let seeds: Vec<u64> = a.report.restarts.iter().map(|r| r.seed).collect();
    assert_eq!(seeds.len(), 3);
    assert_eq!(seeds[0], 42);
    assert!(seeds[1] != seeds[0] && seeds[2] != seeds[1]);
    let (_, c) = fit_mixture(2000, 6, 5, FastIcaParams::default().seed(43).restarts(3));
    assert_ne!(c.report.restarts[0].seed, 42);
}

#[test]
fn every_contrast_and_deflation_converge_on_an_easy_case() {
    let cases = [
        (Contrast::LogCosh, Algorithm::Symmetric),
        (Contrast::Exp, Algorithm::Symmetric),
        (Contrast::Cube, Algorithm::Symmetric),
        (Contrast::LogCosh, Algorithm::Deflation),
        (Contrast::Exp, Algorithm::Deflation),
    ];
    for (contrast, algorithm) in cases {
        let params = FastIcaParams::default()
            .contrast(contrast)
            .algorithm(algorithm)
            .restarts(2);
        let (mix, out) = fit_mixture(4000, 4, 11, params);
        let best = &out.report.restarts[out.report.best_restart];
        assert!(best.converged, "{contrast:?} {algorithm:?}: {best:?}");
        assert_eq!(out.report.contrast, contrast.name());
        assert_eq!(out.report.algorithm, algorithm.name());
        let ai = amari_index(&(&out.unmixing * &mix.mixing)).expect("square");
        assert!(ai < 0.1, "{contrast:?} {algorithm:?}: amari index {ai}");
    }
}

#[test]
fn report_describes_the_run() {
    let params = FastIcaParams::default().restarts(3).tol(1e-5).max_iter(700);
    let (_, out) = fit_mixture(2000, 5, 6, params);
    let r = &out.report;
    assert_eq!(
        (r.frames_total, r.frames_used, r.channels),
        (2000, 2000, 60)
    );
    assert_eq!(r.components, 5);
    assert_eq!((r.tol, r.max_iter), (1e-5, 700));
    assert_eq!(r.restarts.len(), 3);
    assert!(r.best_restart < 3);
    // A short take is explored on every frame, with nothing left to refine.
    assert!(r
        .restarts
        .iter()
        .all(|x| x.frames == 2000 && x.refinement.is_none()));
    let best = r.restarts[r.best_restart].negentropy;
    for x in &r.restarts {
        assert!(x.iterations >= 1 && x.iterations <= 700);
        assert!(x.last_delta.is_finite());
        if x.converged {
            assert!(x.last_delta < 1e-5);
            assert!(x.negentropy <= best + 1e-12);
        }
    }
    assert_eq!(r.eigenvalues.len(), 60);
    assert!(r.eigenvalues.windows(2).all(|w| w[0] >= w[1]));
    assert!(r.variance_kept > 0.9 && r.variance_kept <= 1.0);
}

#[test]
fn one_and_two_components_fit_through_the_small_matrix_paths() {
    for k in [1, 2] {
        for algorithm in [Algorithm::Symmetric, Algorithm::Deflation] {
            let params = FastIcaParams::default().algorithm(algorithm).restarts(2);
            let (mix, out) = fit_mixture(3000, k, 21, params);
            assert_eq!(out.mixing.shape(), (60, k));
            assert!(out
                .mixing
                .iter()
                .chain(out.unmixing.iter())
                .all(|v| v.is_finite()));
            assert!(
                out.report.restarts.iter().all(|r| r.converged),
                "k={k} {algorithm:?}"
            );
            let ai = amari_index(&(&out.unmixing * &mix.mixing)).expect("square");
            assert!(ai < 0.1, "k={k} {algorithm:?}: amari index {ai}");
        }
    }
}

#[test]
fn long_takes_explore_on_a_subsample_and_refine_the_winner_on_every_frame() {
    let params = FastIcaParams::default().seed(5).restarts(3);
    let (mix, out) = fit_mixture(6000, 5, 21, params.clone());
    let r = &out.report;
    assert_eq!(r.restarts.len(), 3);
    for (i, x) in r.restarts.iter().enumerate() {
        // Every 2nd frame of 6000: the restarts explored 3000 frames, not all of them.
        assert_eq!(x.frames, 3000, "restart {i}");
        assert_eq!(x.refinement.is_some(), i == r.best_restart, "restart {i}");
    }
    let best = &r.restarts[r.best_restart];
    let refined = best.refinement.as_ref().expect("the winner is refined");
    assert_eq!(refined.frames, 6000);
    assert!(refined.iterations >= 1 && refined.converged, "{refined:?}");
    assert!(best.solution_converged());
    // The kept solution is the refined one, over every frame: it separates the sources.
    assert!(best_correlations(&mix.sources, &out)
        .iter()
        .all(|&c| c > 0.95));
    let ai = amari_index(&(&out.unmixing * &mix.mixing)).expect("square");
    assert!(ai < 0.05, "amari index {ai}");
    // Deterministic for a seed, subsample and refinement included.
    let (_, again) = fit_mixture(6000, 5, 21, params);
    assert_eq!(again.unmixing, out.unmixing);
    assert_eq!(again.report, out.report);
}
