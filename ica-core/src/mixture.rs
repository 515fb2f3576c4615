//! Seeded synthetic face-like mixtures with a known mixing matrix, for tests and benchmarks
//! (real takes have no ground truth to score a separation against).
//!
//! Sources at 120 Hz cycle through five kinds found in facial motion: gated speech-like
//! oscillations, sparse smooth bumps, blink spikes, a piecewise-constant emotion level with
//! smooth transitions, and a half-wave "jaw" rhythm. Each is standardised to zero mean and unit
//! variance, then the set is made exactly uncorrelated over the frames. The mixing matrix is spatially smooth: markers sit on a unit square, each source
//! moves them along a sum of three Gaussian fields with random 3-D directions, scaled so source
//! `i` has an RMS displacement between 3 mm and 0.5 mm. Markers get rest positions up to
//! 200 mm and every sample i.i.d. Gaussian noise.

use nalgebra::DMatrix;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// Frame rate the sources are generated at.
pub const RATE_HZ: f64 = 120.0;

/// A generated data set and its ground truth.
#[derive(Debug, Clone)]
pub struct Mixture {
    /// `frames x channels`, row-major, millimetres.
    pub samples: Vec<f32>,
    /// Channels per frame.
    pub channels: usize,
    /// Frames.
    pub frames: usize,
    /// The true mixing, `channels x k` (millimetres per unit source).
    pub mixing: DMatrix<f64>,
    /// The true sources, `frames x k`, zero mean and unit variance.
    pub sources: DMatrix<f64>,
}

/// Generates `frames` frames of `channels` channels mixing `k` sources, plus `noise_mm` RMS
/// i.i.d. noise, from `seed`.
pub fn face_like(frames: usize, channels: usize, k: usize, noise_mm: f64, seed: u64) -> Mixture {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut sources = DMatrix::<f64>::zeros(frames, k);
    for i in 0..k {
        let mut s = source(i % 5, frames, &mut rng);
        standardise(&mut s);
        sources.column_mut(i).copy_from_slice(&s);
    }
    decorrelate_columns(&mut sources);
    let mixing = smooth_mixing(channels, k, &mut rng);
    let rest: Vec<f64> = (0..channels)
        .map(|_| rng.random_range(0.0..200.0))
        .collect();
    let signal = &sources * mixing.transpose();
    let mut samples = Vec::with_capacity(frames * channels);
    for f in 0..frames {
        for (c, r) in rest.iter().enumerate() {
            let n: f64 = StandardNormal.sample(&mut rng);
            samples.push((r + signal[(f, c)] + noise_mm * n) as f32);
        }
    }
    Mixture {
        samples,
        channels,
        frames,
        mixing,
        sources,
    }
}

/// One source of the given kind (0..5), unnormalised.
fn source(kind: usize, frames: usize, rng: &mut ChaCha8Rng) -> Vec<f64> {
    let t = |f: usize| f as f64 / RATE_HZ;
    match kind {
        // Speech: a 3-7 Hz syllable oscillation gated by phrases of random loudness and pauses
        // (about half the time silent, which makes it clearly super-Gaussian).
        0 => {
            let hz = rng.random_range(3.0..7.0);
            let phase = rng.random_range(0.0..std::f64::consts::TAU);
            let loudness = [0.0, 0.0, 0.0, 0.6, 1.0, 1.4];
            let gate = smooth(&levels(frames, 0.8, 2.5, &loudness, rng), 12);
            (0..frames)
                .map(|f| gate[f] * (std::f64::consts::TAU * hz * t(f) + phase).sin())
                .collect()
        }
        // Sparse smooth bumps (eyebrow raises and frowns), width 0.15-0.4 s, about one per 2 s.
        1 => bumps(frames, 0.5, 0.15..0.4, true, rng),
        // Blinks: sharp spikes of about 60 ms, about one per 3 s.
        2 => bumps(frames, 1.0 / 3.0, 0.04..0.08, false, rng),
        // Emotion level: held 2-5 s, smooth transitions.
        3 => smooth(&levels(frames, 2.0, 5.0, &[-1.0, 0.0, 0.6, 1.5], rng), 30),
        // Jaw: half-wave rectified rhythm at 1-2 Hz.
        _ => {
            let hz = rng.random_range(1.0..2.0);
            let phase = rng.random_range(0.0..std::f64::consts::TAU);
            (0..frames)
                .map(|f| (std::f64::consts::TAU * hz * t(f) + phase).sin().max(0.0))
                .collect()
        }
    }
}

/// Piecewise-constant values drawn from `choices`, each held `min_s..max_s` seconds.
fn levels(
    frames: usize,
    min_s: f64,
    max_s: f64,
    choices: &[f64],
    rng: &mut ChaCha8Rng,
) -> Vec<f64> {
    let mut out = Vec::with_capacity(frames);
    while out.len() < frames {
        let hold = (rng.random_range(min_s..max_s) * RATE_HZ) as usize;
        let v = choices[rng.random_range(0..choices.len())];
        out.extend(std::iter::repeat_n(v, hold.max(1)));
    }
    out.truncate(frames);
    out
}

/// Gaussian bumps at Poisson times (`rate_hz`), widths drawn from `width_s`, heights 0.5-1.5 with
/// a random sign when `signed`.
fn bumps(
    frames: usize,
    rate_hz: f64,
    width_s: std::ops::Range<f64>,
    signed: bool,
    rng: &mut ChaCha8Rng,
) -> Vec<f64> {
    let mut out = vec![0.0; frames];
    let mut at = 0.0;
    let end = frames as f64 / RATE_HZ;
    loop {
        at += -(1.0 - rng.random::<f64>()).ln() / rate_hz;
        if at >= end {
            break;
        }
        let width = rng.random_range(width_s.clone());
        let mut height = rng.random_range(0.5..1.5);
        if signed && rng.random::<bool>() {
            height = -height;
        }
        let lo = ((at - 4.0 * width) * RATE_HZ).max(0.0) as usize;
        let hi = (((at + 4.0 * width) * RATE_HZ) as usize).min(frames);
        for (f, v) in out.iter_mut().enumerate().take(hi).skip(lo) {
            let d = (f as f64 / RATE_HZ - at) / width;
            *v += height * (-0.5 * d * d).exp();
        }
    }
    out
}

/// Centred moving average over `2 * half + 1` frames (edges shortened).
fn smooth(x: &[f64], half: usize) -> Vec<f64> {
    let mut prefix = vec![0.0; x.len() + 1];
    for (i, v) in x.iter().enumerate() {
        prefix[i + 1] = prefix[i] + v;
    }
    (0..x.len())
        .map(|i| {
            let (lo, hi) = (i.saturating_sub(half), (i + half + 1).min(x.len()));
            (prefix[hi] - prefix[lo]) / (hi - lo) as f64
        })
        .collect()
}

/// Zero mean, unit variance (a constant series stays zero).
fn standardise(x: &mut [f64]) {
    let n = x.len().max(1) as f64;
    let mean = x.iter().sum::<f64>() / n;
    let sd = (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
    for v in x.iter_mut() {
        *v = if sd > 0.0 { (*v - mean) / sd } else { 0.0 };
    }
}

/// Makes the columns exactly uncorrelated with unit variance over the generated frames
/// (`S <- S (S^T S / T)^{-1/2}`, the closest such matrix). ICA outputs are uncorrelated by
/// construction, so sources with chance sample correlation (slow ones over short takes) could
/// never be matched exactly; after this, a perfect separation scores an Amari index of 0.
fn decorrelate_columns(s: &mut DMatrix<f64>) {
    let n = s.nrows().max(1) as f64;
    let gram = s.transpose() * &*s / n;
    let eig = nalgebra::SymmetricEigen::new(gram);
    let mut scaled = eig.eigenvectors.clone();
    for (j, mut col) in scaled.column_iter_mut().enumerate() {
        let d = eig.eigenvalues[j];
        col.scale_mut(if d > 0.0 { 1.0 / d.sqrt() } else { 0.0 });
    }
    let root = scaled * eig.eigenvectors.transpose();
    *s = &*s * root;
}

/// Spatially smooth `channels x k` mixing; source `i` has RMS loading from 3 mm down to 0.5 mm.
fn smooth_mixing(channels: usize, k: usize, rng: &mut ChaCha8Rng) -> DMatrix<f64> {
    let markers = channels.div_ceil(3);
    let pos: Vec<[f64; 2]> = (0..markers)
        .map(|_| [rng.random_range(0.0..1.0), rng.random_range(0.0..1.0)])
        .collect();
    let mut mixing = DMatrix::<f64>::zeros(channels, k);
    for i in 0..k {
        for _ in 0..3 {
            let centre = [rng.random_range(0.0..1.0), rng.random_range(0.0..1.0)];
            let sigma: f64 = rng.random_range(0.15..0.4);
            let dir: [f64; 3] = std::array::from_fn(|_| StandardNormal.sample(&mut *rng));
            for c in 0..channels {
                let p = pos[c / 3];
                let d2 = (p[0] - centre[0]).powi(2) + (p[1] - centre[1]).powi(2);
                mixing[(c, i)] += dir[c % 3] * (-0.5 * d2 / (sigma * sigma)).exp();
            }
        }
        let rms_mm = 3.0 - 2.5 * i as f64 / (k.max(2) - 1) as f64;
        let rms = (mixing.column(i).norm_squared() / channels as f64).sqrt();
        if rms > 0.0 {
            mixing.column_mut(i).scale_mut(rms_mm / rms);
        }
    }
    mixing
}
