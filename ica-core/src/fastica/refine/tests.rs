use super::*;
use crate::fastica::{deflation, random_start, symmetric};
use crate::input::FitData;
use crate::mixture;
use crate::whiten::{whiten, Components};

/// Whitened face-like frames, `m x frames`.
fn whitened(frames: usize, m: usize, seed: u64) -> DMatrix<f64> {
    let mix = mixture::face_like(frames, 30, m, 0.2, seed);
    let data = FitData::new(&mix.samples, 30).expect("whole frames");
    whiten(&data, Components::Fixed(m))
        .expect("whitens")
        .whitened
}

/// The chunked iteration over `z` cut every `chunk` frames.
fn chunked(z: &DMatrix<f64>, w0: DMatrix<f64>, s: RefineSettings, chunk: usize) -> RefineOutcome {
    let m = z.nrows();
    refine_chunked(w0, s, &mut |each: &mut ChunkSink<'_, f64>| {
        z.as_slice().chunks(chunk * m).for_each(&mut *each);
    })
    .expect("whole frames")
}

fn settings(contrast: Contrast, algorithm: Algorithm) -> RefineSettings {
    RefineSettings {
        contrast,
        algorithm,
        tol: 1e-6,
        max_iter: 300,
    }
}

#[test]
fn chunked_iteration_reproduces_the_in_memory_one() {
    let z = whitened(6_000, 5, 4);
    for contrast in [Contrast::LogCosh, Contrast::Exp, Contrast::Cube] {
        for algorithm in [Algorithm::Symmetric, Algorithm::Deflation] {
            let s = settings(contrast, algorithm);
            let w0 = random_start(5, 17);
            let want = match algorithm {
                Algorithm::Symmetric => {
                    let mut ws = symmetric::Workspace::new(5, z.ncols());
                    symmetric::run(&z, w0.clone(), contrast, s.tol, s.max_iter, &mut ws)
                }
                Algorithm::Deflation => deflation::run(&z, &w0, contrast, s.tol, s.max_iter),
            };
            for chunk in [6_000, 1_000, 999, 13] {
                let got = chunked(&z, w0.clone(), s, chunk);
                let case = format!("{contrast:?} {algorithm:?} chunk {chunk}");
                assert_eq!(got.converged, want.converged, "{case}");
                assert!(got.iterations.abs_diff(want.iterations) <= 1, "{case}");
                let diff = (&got.w - &want.w).amax();
                // Deflation carries each component's rounding into the next ones.
                assert!(diff < 1e-8, "{case}: |W - W_mem| = {diff:e}");
            }
        }
    }
}

#[test]
fn a_long_run_takes_the_same_damped_steps() {
    // An unreachable tolerance runs both to the cap, past the step halvings at 40 and 80.
    let z = whitened(1_500, 6, 8);
    let s = RefineSettings {
        contrast: Contrast::Cube,
        algorithm: Algorithm::Symmetric,
        tol: 1e-30,
        max_iter: 100,
    };
    let w0 = random_start(6, 3);
    let mut ws = symmetric::Workspace::new(6, z.ncols());
    let want = symmetric::run(&z, w0.clone(), s.contrast, s.tol, s.max_iter, &mut ws);
    let mut r = Refiner::new(w0, s);
    while !r.is_done() {
        let mut acc = r.accumulator();
        z.as_slice()
            .chunks(100 * 6)
            .for_each(|c| acc.add_chunk(c).expect("whole frames"));
        r.handle_update(acc).expect("frames");
    }
    assert_eq!(r.step.mu, 0.25, "halved at 40 and 80");
    let got = r.outcome().expect("done");
    assert_eq!((got.iterations, want.iterations), (100, 100));
    assert!(!got.converged && !want.converged);
    assert!((&got.w - &want.w).amax() < 1e-9);
}

#[test]
fn stale_or_empty_accumulators_are_refused() {
    let z = whitened(2_000, 3, 2);
    let mut r = Refiner::new(
        random_start(3, 1),
        settings(Contrast::LogCosh, Algorithm::Symmetric),
    );
    let stale = r.accumulator();
    let mut acc = r.accumulator();
    acc.add_chunk(z.as_slice()).expect("whole frames");
    assert_eq!(
        r.handle_update(r.accumulator()),
        Err(FitError::TooFewFrames {
            used: 0,
            total: 0,
            needed: 1
        })
    );
    r.handle_update(acc).expect("one step");
    assert_eq!(r.handle_update(stale), Err(FitError::AccumulatorMismatch));
    let mut a = r.accumulator();
    assert_eq!(
        a.add_chunk(&z.as_slice()[..7]),
        Err(FitError::RaggedSamples {
            len: 7,
            channels: 3
        })
    );
}
