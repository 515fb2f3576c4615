//! Streaming moments (issue 18): stable with large offsets over a million frames, equal to a
//! two-pass reference for any cut and merge order, and the in-memory rule for missing samples.

use ica_core::fit::{FitData, FitError};
use ica_core::whiten::Moments;
use nalgebra::DMatrix;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Two-pass mean and unbiased covariance of the rows of `x` (`frames x p`) where `keep` holds.
fn two_pass(x: &[f64], p: usize, keep: impl Fn(usize) -> bool) -> (Vec<f64>, DMatrix<f64>) {
    let rows: Vec<&[f64]> = x
        .chunks_exact(p)
        .enumerate()
        .filter(|(f, _)| keep(*f))
        .map(|(_, r)| r)
        .collect();
    let n = rows.len() as f64;
    let mean: Vec<f64> = (0..p)
        .map(|c| rows.iter().map(|r| r[c]).sum::<f64>() / n)
        .collect();
    let cov = DMatrix::from_fn(p, p, |i, j| {
        rows.iter()
            .map(|r| (r[i] - mean[i]) * (r[j] - mean[j]))
            .sum::<f64>()
            / (n - 1.0)
    });
    (mean, cov)
}

/// Moments of `data` cut into chunks of `chunk` frames, one partial per chunk merged left to
/// right (`tree = false`) or pairwise (`tree = true`).
fn partials<T: Copy + Into<f64>>(data: FitData<'_, T>, chunk: usize, tree: bool) -> Moments {
    let mut parts: Vec<Moments> = (0..data.frames())
        .step_by(chunk)
        .map(|s| {
            let mut m = Moments::new(data.channels()).starting_at(s);
            m.add_chunk(&data.slice_frames(s, (s + chunk).min(data.frames())))
                .expect("finite");
            m
        })
        .collect();
    while parts.len() > 1 {
        let stride = if tree { 2 } else { parts.len() };
        let mut next = Vec::new();
        for group in parts.chunks(stride) {
            let mut it = group.iter().cloned();
            let mut acc = it.next().expect("non-empty group");
            it.for_each(|m| acc.merge(m).expect("same width"));
            next.push(acc);
        }
        parts = next;
    }
    parts.pop().expect("at least one chunk")
}

fn sequential<T: Copy + Into<f64>>(data: FitData<'_, T>, chunk: usize) -> Moments {
    let mut m = Moments::new(data.channels());
    for s in (0..data.frames()).step_by(chunk) {
        m.add_chunk(&data.slice_frames(s, (s + chunk).min(data.frames())))
            .expect("finite");
    }
    m
}

fn assert_close(m: &Moments, mean: &[f64], cov: &DMatrix<f64>, tol: f64) {
    let scale = cov.amax();
    for (c, (a, b)) in m.mean().iter().zip(mean).enumerate() {
        assert!((a - b).abs() <= tol * scale.sqrt(), "mean[{c}] {a} vs {b}");
    }
    let err = (m.covariance() - cov).amax() / scale;
    assert!(err <= tol, "covariance relative error {err:e}");
}

#[test]
fn a_1e4_mm_offset_over_a_million_frames_is_harmless() {
    // Six correlated channels of exact multiples of 1/64 mm around 10 m, period 1000 frames: the
    // f32 samples are exact, and the moments of 1e6 frames are those of one period.
    const P: usize = 6;
    const PERIOD: usize = 1000;
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let base: Vec<[i32; 2]> = (0..PERIOD)
        .map(|_| [rng.random_range(-640..640), rng.random_range(-320..320)])
        .collect();
    let value = |t: usize, c: usize| {
        let [a, b] = base[t % PERIOD];
        1e4 + (a * (c as i32 + 1) + b * (3 - c as i32)) as f64 / 64.0
    };
    let period: Vec<f64> = (0..PERIOD * P).map(|i| value(i / P, i % P)).collect();
    let (mean, cov_period) = two_pass(&period, P, |_| true);
    let frames = 1_000_000;
    let samples: Vec<f32> = (0..frames * P)
        .map(|i| value(i / P, i % P) as f32)
        .collect();
    // The same M2 over 1000 periods, divided by n - 1 instead of PERIOD - 1.
    let scale = (PERIOD as f64 - 1.0) * (frames / PERIOD) as f64 / (frames as f64 - 1.0);
    let cov = cov_period * scale;
    let data = FitData::new(&samples, P).expect("whole frames");
    for m in [sequential(data, 4096), partials(data, 65_536, true)] {
        assert_eq!((m.frames_total(), m.frames_used()), (frames, frames));
        assert_close(&m, &mean, &cov, 1e-12);
    }
}

/// `frames x p` data with offsets up to 2 m, an occluded marker now and then, channel 5 never
/// seen (NaN), and the frames that count under the in-memory rule.
fn occluded(frames: usize, p: usize) -> (Vec<f64>, Vec<bool>) {
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let offsets: Vec<f64> = (0..p).map(|_| rng.random_range(-2000.0..2000.0)).collect();
    let mut x = Vec::with_capacity(frames * p);
    let mut missing = vec![false; frames * p];
    for f in 0..frames {
        let common: f64 = rng.random_range(-5.0..5.0);
        for (c, o) in offsets.iter().enumerate() {
            x.push(o + common * (c as f64 * 0.3) + rng.random_range(-1.0..1.0));
        }
        x[f * p + 5] = f64::NAN;
        missing[f * p + 5] = true;
        if f % 13 == 4 {
            missing[f * p + 1] = true;
            x[f * p + 1] = f64::INFINITY;
        }
    }
    (x, missing)
}

#[test]
fn any_cut_and_merge_order_gives_the_two_pass_moments_of_the_used_frames() {
    let (frames, p) = (5_000, 9);
    let (x, missing) = occluded(frames, p);
    let data = FitData::new(&x, p)
        .and_then(|d| d.with_missing(&missing))
        .expect("shapes");
    let used = |f: usize| f % 13 != 4;
    let zeroed: Vec<f64> = x
        .iter()
        .zip(&missing)
        .map(|(&v, &m)| if m { 0.0 } else { v })
        .collect();
    let (mean, cov) = two_pass(&zeroed, p, used);
    let runs = [
        sequential(data, frames),
        sequential(data, 7),
        partials(data, 333, false),
        partials(data, 333, true),
        partials(data, 1, true),
    ];
    for m in &runs {
        assert_eq!(m.frames_used(), (0..frames).filter(|&f| used(f)).count());
        assert_eq!(m.frames_total(), frames);
        assert!(m.missing_everywhere()[5]);
        assert_eq!(m.missing_everywhere().iter().filter(|&&b| b).count(), 1);
        assert_eq!(m.mean()[5], 0.0);
        assert_close(m, &mean, &cov, 1e-12);
        assert!(m.frame_is_used(Some(&missing[..p])));
        assert!(!m.frame_is_used(Some(&missing[4 * p..5 * p])));
        assert!(!m.frame_is_used(None), "channel 5 is never present");
    }
}

#[test]
fn a_channel_seen_late_excludes_the_frames_that_missed_it() {
    // Channel 2 is missing in the first 300 frames only: those frames were never complete.
    let (frames, p) = (1_000, 4);
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let x: Vec<f64> = (0..frames * p)
        .map(|_| rng.random_range(100.0..101.0))
        .collect();
    let mut missing = vec![false; frames * p];
    (0..300).for_each(|f| missing[f * p + 2] = true);
    let data = FitData::new(&x, p)
        .and_then(|d| d.with_missing(&missing))
        .expect("shapes");
    let (mean, cov) = two_pass(&x, p, |f| f >= 300);
    for m in [
        sequential(data, 100),
        sequential(data, 1000),
        partials(data, 100, true),
    ] {
        assert_eq!((m.frames_used(), m.frames_total()), (700, 1000));
        assert!(m.missing_everywhere().iter().all(|&b| !b));
        assert_close(&m, &mean, &cov, 1e-12);
    }
}

#[test]
fn errors_name_the_session_frame_and_add_nothing() {
    let mut x = vec![1.0f32; 40 * 4];
    x[37 * 4 + 1] = f32::NAN;
    let data = FitData::new(&x, 4).expect("whole frames");
    let mut m = Moments::new(4).starting_at(1_000);
    m.add_chunk(&data.slice_frames(0, 20)).expect("finite");
    let err = m.add_chunk(&data.slice_frames(20, 40)).expect_err("NaN");
    assert!(
        matches!(
            err,
            FitError::NonFinite {
                frame: 1_037,
                channel: 1,
                ..
            }
        ),
        "{err}"
    );
    assert_eq!((m.frames_total(), m.frames_used()), (20, 20));
    let narrow = FitData::new(&x[..12], 3).expect("whole frames");
    assert_eq!(
        m.add_chunk(&narrow),
        Err(FitError::ChannelMismatch {
            expected: 4,
            got: 3
        })
    );
    assert_eq!(
        m.merge(Moments::new(5)),
        Err(FitError::ChannelMismatch {
            expected: 4,
            got: 5
        })
    );
}
