//! Whitening one chunk of frames into a caller buffer: `z = Λ^{-1/2} Eᵀ (x - mean)` for the used
//! frames, in the layout the FastICA kernels read (frame after frame, `m` values each).

use super::stats::frame_is_used;
use super::Whitener;
use crate::input::{FitData, FitError};
use crate::linalg::{cols, cols_mut, product};

/// Used frames centred per gemm call.
const BLOCK_FRAMES: usize = 256;

/// A sample type whitened values are written as: `f32` (half the spill file) or `f64` (exact).
pub trait FromF64: Copy + Into<f64> {
    /// The nearest value of this type.
    fn from_f64(value: f64) -> Self;
}

impl FromF64 for f32 {
    fn from_f64(value: f64) -> Self {
        value as f32
    }
}

impl FromF64 for f64 {
    fn from_f64(value: f64) -> Self {
        value
    }
}

impl Whitener {
    /// Whitens the used frames of `chunk` (see [`Whitener::frame_is_used`]) into `out`, which is
    /// cleared first and holds `used x m` values afterwards (frame after frame); returns the
    /// number of used frames. `scratch` is working memory: keep it across calls and nothing is
    /// allocated once both buffers have grown to the chunk size.
    ///
    /// # Errors
    /// [`FitError::ChannelMismatch`] for a chunk of another width, [`FitError::NonFinite`] for a
    /// non-finite sample on a live channel of a used frame (the data changed since the
    /// statistics were taken; the frame is counted within the chunk).
    pub fn whiten_into<T: Copy + Into<f64>, E: FromF64>(
        &self,
        chunk: &FitData<'_, T>,
        out: &mut Vec<E>,
        scratch: &mut Vec<f64>,
    ) -> Result<usize, FitError> {
        if chunk.channels() != self.channels() {
            return Err(FitError::ChannelMismatch {
                expected: self.channels(),
                got: chunk.channels(),
            });
        }
        let (live, m) = (self.live_channels.len(), self.components());
        let all_live = live == self.channels();
        scratch.resize((live + m) * BLOCK_FRAMES, 0.0);
        let (block, z) = scratch.split_at_mut(live * BLOCK_FRAMES);
        out.clear();
        let (mut filled, mut used) = (0, 0);
        for f in 0..chunk.frames() {
            if !frame_is_used(&self.missing_everywhere, chunk.frame_missing(f)) {
                continue;
            }
            let col = &mut block[filled * live..(filled + 1) * live];
            let values = chunk.frame(f);
            // With every channel live (the usual case) the frame is one contiguous run.
            if all_live {
                for ((dst, &v), &mu) in col.iter_mut().zip(values).zip(&self.mean) {
                    *dst = v.into() - mu;
                }
            } else {
                for (dst, &c) in col.iter_mut().zip(&self.live_channels) {
                    *dst = values[c].into() - self.mean[c];
                }
            }
            if let Some(i) = col.iter().position(|v| !v.is_finite()) {
                let channel = self.live_channels[i];
                return Err(FitError::NonFinite {
                    frame: f,
                    channel,
                    value: values[channel].into(),
                });
            }
            filled += 1;
            used += 1;
            if filled == BLOCK_FRAMES {
                self.project_block(block, z, filled, out);
                filled = 0;
            }
        }
        if filled > 0 {
            self.project_block(block, z, filled, out);
        }
        Ok(used)
    }

    /// Appends `rows · block` for the first `filled` centred frames of `block` to `out`.
    fn project_block<E: FromF64>(
        &self,
        block: &[f64],
        z: &mut [f64],
        filled: usize,
        out: &mut Vec<E>,
    ) {
        let (live, m) = (self.live_channels.len(), self.components());
        product(
            cols_mut(z, m, filled),
            cols(self.rows.as_slice(), m, live),
            cols(block, live, filled),
        );
        out.extend(z[..m * filled].iter().map(|&v| E::from_f64(v)));
    }
}
