//! Resampling a take to another frame rate (linear interpolation per marker).

use crate::Take;

impl Take {
    /// The take resampled to `rate_hz` by linear interpolation between neighbouring frames.
    ///
    /// The new take spans the same time (its last frame is at or before the old last frame's
    /// time). A new sample is missing when either neighbour it interpolates is missing. The first
    /// frame number is kept; frames are renumbered consecutively at the new rate.
    ///
    /// # Panics
    /// If `rate_hz` is not positive and finite.
    pub fn resampled(&self, rate_hz: f64) -> Take {
        assert!(
            rate_hz.is_finite() && rate_hz > 0.0,
            "rate must be positive"
        );
        let mut out = Take::new(self.labels.clone(), rate_hz, self.first_frame);
        out.source_units = self.source_units;
        let n = self.n_frames();
        if n == 0 {
            return out;
        }
        let duration = (n - 1) as f64 / self.rate_hz;
        let frames = (duration * rate_hz + 1e-9).floor() as usize + 1;
        let markers = self.n_markers();
        let mut xyz = vec![0.0f32; markers * 3];
        let mut missing = vec![false; markers];
        for f in 0..frames {
            let pos = f as f64 / rate_hz * self.rate_hz;
            let lo = (pos.floor() as usize).min(n - 1);
            let hi = (lo + 1).min(n - 1);
            let t = (pos - lo as f64) as f32;
            for m in 0..markers {
                // A sample that lands exactly on an old frame needs only that frame.
                let gone = self.is_missing(lo, m) || (t > 0.0 && self.is_missing(hi, m));
                missing[m] = gone;
                if gone {
                    continue;
                }
                for a in 0..3 {
                    let p = self.positions[(lo * markers + m) * 3 + a];
                    let q = self.positions[(hi * markers + m) * 3 + a];
                    xyz[m * 3 + a] = p + (q - p) * t;
                }
            }
            out.push_frame(&xyz, &missing);
        }
        out
    }
}

#[cfg(test)]
mod tests;
