//! The streaming fit (issue 18) gives what the in-memory fit gives on the same frames: whole
//! takes, missing samples and dead channels, one chunk or many, partials merged in any grouping.

use std::convert::Infallible;

use ica_core::fit::{
    mixture, Algorithm, FastIcaParams, FitData, FitOutput, MemorySource, MemoryStore, Pass,
    StreamFit,
};
use ica_core::whiten::{Moments, Whitener};
use nalgebra::DMatrix;

/// Largest `|a - b|` over the largest `|b|`.
fn rel_diff(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    assert_eq!(a.shape(), b.shape());
    (a - b).amax() / b.amax()
}

/// Streaming output `s` matches in-memory output `m` within `tol` (relative), order and sign
/// included.
fn assert_same(s: &FitOutput, m: &FitOutput, tol: f64) {
    let (rs, rm) = (&s.report, &m.report);
    assert_eq!(
        (rs.frames_total, rs.frames_used, rs.channels, rs.components),
        (rm.frames_total, rm.frames_used, rm.channels, rm.components)
    );
    assert_eq!(rs.dead_channels, rm.dead_channels);
    assert_eq!(rs.best_restart, rm.best_restart);
    let scale = m.mean.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    for (a, b) in s.mean.iter().zip(&m.mean) {
        assert!((a - b).abs() <= 1e-12 * scale, "mean {a} vs {b}");
    }
    for (a, b) in rs.eigenvalues.iter().zip(&rm.eigenvalues) {
        assert!(
            (a - b).abs() <= 1e-9 * rm.eigenvalues[0],
            "eigenvalue {a} vs {b}"
        );
    }
    assert!((rs.variance_kept - rm.variance_kept).abs() < 1e-12);
    let (dm, du) = (
        rel_diff(&s.mixing, &m.mixing),
        rel_diff(&s.unmixing, &m.unmixing),
    );
    assert!(dm < tol && du < tol, "mixing {dm:e}, unmixing {du:e}");
    // A component's variance is quadratic in its mixing column: twice the relative error.
    for (a, b) in s.component_variance.iter().zip(&m.component_variance) {
        assert!((a - b).abs() <= 2.0 * tol * b, "variance {a} vs {b}");
    }
    assert_eq!(rs.restarts.len(), rm.restarts.len());
    for (a, b) in rs.restarts.iter().zip(&rm.restarts) {
        assert_eq!(
            (a.seed, a.frames, a.converged),
            (b.seed, b.frames, b.converged)
        );
        assert!(a.iterations.abs_diff(b.iterations) <= 1, "{a:?} vs {b:?}");
        assert!((a.negentropy - b.negentropy).abs() <= 1e-6 * b.negentropy.abs().max(1e-12));
        assert_eq!(a.refinement.is_some(), b.refinement.is_some());
        if let (Some(x), Some(y)) = (&a.refinement, &b.refinement) {
            assert_eq!((x.frames, x.converged), (y.frames, y.converged));
            assert!(x.iterations.abs_diff(y.iterations) <= 1, "{x:?} vs {y:?}");
            assert!((x.negentropy - y.negentropy).abs() <= 1e-6 * y.negentropy);
        }
    }
    assert_eq!(rs.stability.len(), rm.stability.len());
    for (a, b) in rs.stability.iter().zip(&rm.stability) {
        assert!((a - b).abs() < 1e-6, "stability {a} vs {b}");
    }
    assert!(s.sources.is_none() && s.used_frames.is_empty());
}

/// Both fits of `data` in chunks of `chunk_frames`, the whitened frames stored as f64.
fn both(
    params: &FastIcaParams,
    data: FitData<'_, f32>,
    chunk_frames: usize,
) -> (FitOutput, FitOutput) {
    let mut source = MemorySource::new(data, chunk_frames);
    let mut store = MemoryStore::<f64>::new(chunk_frames);
    let streamed = params.fit_stream(&mut source, &mut store).expect("streams");
    (streamed, params.fit(&data).expect("fits"))
}

#[test]
fn long_take_matches_the_in_memory_fit_for_one_chunk_and_many() {
    let mix = mixture::face_like(12_000, 60, 6, 0.2, 3);
    let data = FitData::new(&mix.samples, 60).expect("whole frames");
    let params = FastIcaParams::default().n_components(6).restarts(3).seed(2);
    for chunk in [12_000, 977, 64] {
        let (s, m) = both(&params, data, chunk);
        let best = &m.report.restarts[m.report.best_restart];
        assert!(best.refinement.is_some(), "the subsampled path is tested");
        assert_same(&s, &m, 1e-8);
    }
}

#[test]
fn missing_samples_and_dead_channels_match() {
    let mix = mixture::face_like(12_000, 30, 4, 0.2, 5);
    let mut x = mix.samples.clone();
    let mut missing = vec![false; x.len()];
    for f in 0..12_000 {
        x[f * 30 + 7] = 123.5; // a stuck marker coordinate
        x[f * 30 + 20] = f32::NAN; // a channel never observed
        missing[f * 30 + 20] = true;
        if f % 10 == 3 {
            for c in 9..12 {
                missing[f * 30 + c] = true;
                x[f * 30 + c] = 1e30;
            }
        }
    }
    let data = FitData::new(&x, 30)
        .and_then(|d| d.with_missing(&missing))
        .expect("shapes match");
    let params = FastIcaParams::default().n_components(4);
    for chunk in [12_000, 501, 7] {
        let (s, m) = both(&params, data, chunk);
        assert_eq!(s.report.dead_channels, vec![7, 20]);
        assert_eq!(s.report.frames_used, 10_800);
        assert_eq!(s.mean[20], 0.0);
        assert!((s.mean[7] - 123.5).abs() < 1e-9);
        assert_same(&s, &m, 1e-8);
    }
}

#[test]
fn short_takes_single_restarts_and_deflation_match() {
    let short = mixture::face_like(3_000, 30, 4, 0.2, 8);
    let long = mixture::face_like(8_000, 30, 4, 0.2, 9);
    let cases = [
        (&short, FastIcaParams::default().n_components(4)),
        (&long, FastIcaParams::default().n_components(4).restarts(1)),
        (
            &long,
            FastIcaParams::default()
                .n_components(4)
                .restarts(2)
                .algorithm(Algorithm::Deflation),
        ),
        (&long, FastIcaParams::default().variance_target(0.95)),
    ];
    for (mix, params) in cases {
        let data = FitData::new(&mix.samples, 30).expect("whole frames");
        let (s, m) = both(&params, data, 333);
        assert_same(&s, &m, 1e-8);
    }
}

#[test]
fn f32_spill_stays_close() {
    let mix = mixture::face_like(12_000, 60, 6, 0.2, 3);
    let data = FitData::new(&mix.samples, 60).expect("whole frames");
    let params = FastIcaParams::default().n_components(6);
    let mut store = MemoryStore::<f32>::new(1000);
    let s = params
        .fit_stream(&mut MemorySource::new(data, 1000), &mut store)
        .expect("streams");
    let m = params.fit(&data).expect("fits");
    assert_eq!(store.values().len(), 12_000 * 6);
    // Whitened values rounded to f32 (relative 6e-8) move the rotation by about as much.
    assert_same(&s, &m, 1e-6);
}

/// Runs a [`StreamFit`] the way a parallel driver would: one partial per chunk, merged as a
/// balanced tree (`tree = true`) or left to right.
fn grouped_fit(
    params: &FastIcaParams,
    data: FitData<'_, f32>,
    chunk: usize,
    tree: bool,
) -> FitOutput {
    let frames = data.frames();
    let chunks: Vec<FitData<'_, f32>> = (0..frames)
        .step_by(chunk)
        .map(|s| data.slice_frames(s, (s + chunk).min(frames)))
        .collect();
    let mut fit = StreamFit::new(params, data.channels()).expect("params");
    let mut z_chunks: Vec<Vec<f32>> = Vec::new();
    loop {
        match fit.poll_pass() {
            Pass::Moments => {
                let parts = chunks.iter().scan(0, |first, c| {
                    let mut m = Moments::new(c.channels()).starting_at(*first);
                    *first += c.frames();
                    m.add_chunk(c).expect("finite");
                    Some(m)
                });
                let merged = reduce(parts.collect(), tree, |a, b| {
                    a.merge(b).expect("same width")
                });
                fit.handle_moments(merged).expect("whitens");
            }
            Pass::Whiten => {
                let w: &Whitener = fit.whitener().expect("whitening pass");
                let mut scratch = Vec::new();
                z_chunks = chunks
                    .iter()
                    .map(|c| {
                        let mut z = Vec::new();
                        w.whiten_into(c, &mut z, &mut scratch).expect("whitens");
                        z
                    })
                    .collect();
                let mut sub = fit.subsample().expect("whitening pass");
                z_chunks
                    .iter()
                    .for_each(|z| sub.push(z).expect("whole frames"));
                fit.handle_whitened(sub).expect("restarts");
            }
            Pass::Update => {
                let parts = z_chunks.iter().map(|z| {
                    let mut acc = fit.update_accumulator().expect("update pass");
                    acc.add_chunk(z).expect("whole frames");
                    acc
                });
                let acc = reduce(parts.collect(), tree, |a, b| a.merge(b).expect("same step"));
                fit.handle_update(acc).expect("iterates");
            }
            Pass::Sources => {
                let parts = z_chunks.iter().map(|z| {
                    let mut s = fit.source_moments().expect("sources pass");
                    s.add_chunk(z).expect("whole frames");
                    s
                });
                let sums = reduce(parts.collect(), tree, |a, b| a.merge(b).expect("same w"));
                fit.handle_sources(sums).expect("assembles");
            }
            Pass::Done => return fit.finish().expect("done"),
        }
    }
}

/// Folds `items` left to right, or as a balanced binary tree.
fn reduce<T>(mut items: Vec<T>, tree: bool, merge: impl Fn(&mut T, T) + Copy) -> T {
    if !tree {
        let mut it = items.into_iter();
        let mut acc = it.next().expect("at least one chunk");
        it.for_each(|x| merge(&mut acc, x));
        return acc;
    }
    while items.len() > 1 {
        let mut next = Vec::with_capacity(items.len().div_ceil(2));
        let mut it = items.into_iter();
        while let Some(mut a) = it.next() {
            if let Some(b) = it.next() {
                merge(&mut a, b);
            }
            next.push(a);
        }
        items = next;
    }
    items.pop().expect("at least one chunk")
}

#[test]
fn partials_merged_in_any_grouping_match() {
    let mix = mixture::face_like(12_000, 60, 6, 0.2, 3);
    let data = FitData::new(&mix.samples, 60).expect("whole frames");
    let params = FastIcaParams::default().n_components(6).restarts(3).seed(2);
    let m = params.fit(&data).expect("fits");
    let left = grouped_fit(&params, data, 1_500, false);
    let tree = grouped_fit(&params, data, 1_500, true);
    // f32 whitened chunks here, as a daemon would spill them.
    assert_same(&left, &m, 1e-6);
    assert_same(&tree, &m, 1e-6);
    // Same cut, same merge order: bit-identical (what a deterministic parallel driver relies on).
    let again = grouped_fit(&params, data, 1_500, true);
    assert_eq!(again.unmixing, tree.unmixing);
    assert_eq!(again.report, tree.report);
}

#[test]
fn passes_out_of_order_or_inconsistent_are_typed_errors() {
    use ica_core::FitError;
    let mix = mixture::face_like(6_000, 12, 3, 0.2, 1);
    let data = FitData::new(&mix.samples, 12).expect("whole frames");
    let params = FastIcaParams::default().n_components(3);
    let mut fit = StreamFit::new(&params, 12).expect("params");
    assert!(matches!(
        fit.update_accumulator(),
        Err(FitError::UnexpectedPass {
            expected: Pass::Moments,
            got: Pass::Update
        })
    ));
    assert_eq!(
        fit.handle_moments(Moments::new(11)),
        Err(FitError::ChannelMismatch {
            expected: 12,
            got: 11
        })
    );
    let mut moments = fit.moments();
    moments.add_chunk(&data).expect("finite");
    fit.handle_moments(moments).expect("whitens");
    // A whitening pass that skipped a chunk.
    let mut sub = fit.subsample().expect("whitening pass");
    let (mut z, mut scratch) = (Vec::<f64>::new(), Vec::new());
    let half = data.slice_frames(0, 3_000);
    let w = fit.whitener().expect("whitener");
    w.whiten_into(&half, &mut z, &mut scratch).expect("whitens");
    sub.push(&z).expect("whole frames");
    assert_eq!(
        fit.handle_whitened(sub),
        Err(FitError::FrameCountMismatch {
            pass: Pass::Whiten,
            expected: 6_000,
            got: 3_000
        })
    );
    let err: Result<_, ica_core::fit::StreamError<Infallible, Infallible>> =
        FastIcaParams::default().n_components(13).fit_stream(
            &mut MemorySource::new(data, 100),
            &mut MemoryStore::<f64>::new(100),
        );
    assert!(matches!(
        err,
        Err(ica_core::fit::StreamError::Fit(
            FitError::ComponentsExceedRank { .. }
        ))
    ));
}
