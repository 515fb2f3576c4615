//! The second differences the noise estimate reads ([`ica_core::measure::noise_of_differences`]),
//! collected take by take in room reserved once for the whole session.
//!
//! Every take's count is known before the pass (every `stride`-th frame from its second), so
//! each channel gets a fixed run of slots in one buffer: no vector grows, none is copied, and a
//! difference is written whether or not it is kept (the run's length moves only when it is),
//! which keeps the loop free of branches. The values and each channel's multiset are those the
//! per-channel vectors held before, so the estimate is the same number.

use ica_core::measure::noise_of_differences;

/// Second differences per channel: channel `ch`'s are `values[ch * slots..][..len[ch]]`.
#[derive(Debug)]
pub(super) struct NoiseDifferences {
    values: Vec<f64>,
    len: Vec<usize>,
    /// Room per channel: the session's most, plus one for the write that is not kept.
    slots: usize,
    /// Slots the takes so far may have filled: no channel's length is beyond it.
    used: usize,
    stride: usize,
}

impl NoiseDifferences {
    /// Room for `channels` channels over takes of `take_frames` frames, read every `stride`
    /// frames. The buffer is zeroed lazily by the system, so pages never written are never
    /// touched.
    pub(super) fn new(channels: usize, take_frames: &[usize], stride: usize) -> Self {
        let stride = stride.max(1);
        let most: usize = take_frames
            .iter()
            .map(|&t| t.saturating_sub(2).div_ceil(stride))
            .sum();
        let slots = most + 1;
        Self {
            values: vec![0.0; channels * slots],
            len: vec![0; channels],
            slots,
            used: 0,
            stride,
        }
    }

    /// Adds a take's second differences: `samples` is frames x channels, `missing` frames x
    /// markers (three channels each). A difference is kept where its marker is present in all
    /// three frames.
    ///
    /// # Panics
    /// If the take has more frames than [`Self::new`] was told of (an internal invariant).
    pub(super) fn add_take(&mut self, samples: &[f32], missing: &[bool], frames: usize) {
        let c = self.len.len();
        let n = c / 3;
        self.used += frames.saturating_sub(2).div_ceil(self.stride);
        assert!(self.used < self.slots, "more frames than the session holds");
        for f in (1..frames.saturating_sub(1)).step_by(self.stride) {
            let x = &samples[(f - 1) * c..(f + 2) * c];
            let m = &missing[(f - 1) * n..(f + 2) * n];
            let (x0, x1, x2) = (&x[..c], &x[c..2 * c], &x[2 * c..]);
            let (m0, m1, m2) = (&m[..n], &m[n..2 * n], &m[2 * n..]);
            for k in 0..n {
                let keep = usize::from(!(m0[k] || m1[k] || m2[k]));
                for ch in 3 * k..3 * k + 3 {
                    let d2 = f64::from(x0[ch]) - 2.0 * f64::from(x1[ch]) + f64::from(x2[ch]);
                    let len = &mut self.len[ch];
                    self.values[ch * self.slots + *len] = d2;
                    *len += keep;
                }
            }
        }
    }

    /// The capture's noise per coordinate (mm), on the current rayon pool (the values are
    /// reordered).
    pub(super) fn noise_mm(&mut self) -> f64 {
        let mut runs: Vec<&mut [f64]> = self
            .values
            .chunks_exact_mut(self.slots.max(1))
            .zip(&self.len)
            .map(|(run, &len)| &mut run[..len])
            .collect();
        noise_of_differences(&mut runs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same numbers as per-channel vectors filled frame by frame, across takes, gaps and
    /// a stride.
    #[test]
    fn matches_per_channel_vectors() {
        let (n, c, stride) = (4, 12, 2);
        let takes = [29usize, 2, 40];
        let mut noise = NoiseDifferences::new(c, &takes, stride);
        let mut expected = vec![Vec::new(); c];
        let mut seed = 7u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 33) as f32 / 1e6
        };
        for (t, &frames) in takes.iter().enumerate() {
            let samples: Vec<f32> = (0..frames * c).map(|_| next()).collect();
            let missing: Vec<bool> = (0..frames * n).map(|i| (i + t) % 7 == 3).collect();
            noise.add_take(&samples, &missing, frames);
            for f in (1..frames.saturating_sub(1)).step_by(stride) {
                for ch in 0..c {
                    let gone = (f - 1..=f + 1).any(|g| missing[g * n + ch / 3]);
                    if !gone {
                        let at = |g: usize| f64::from(samples[g * c + ch]);
                        expected[ch].push(at(f - 1) - 2.0 * at(f) + at(f + 1));
                    }
                }
            }
        }
        for (ch, want) in expected.iter().enumerate() {
            assert_eq!(
                &noise.values[ch * noise.slots..][..noise.len[ch]],
                &want[..]
            );
        }
        assert!(expected.iter().any(|e| e.len() >= 10));
        let got = noise.noise_mm();
        assert_eq!(got.to_bits(), noise_of_differences(&mut expected).to_bits());
    }
}
