//! The training data as the fit reads it: a borrowed frames x channels matrix.

use super::FitError;

/// Training data: `frames x channels` samples, row-major (one frame after another, each frame
/// `channels = markers x 3` values `x0 y0 z0 x1 y1 z1 ...`), borrowed from the caller.
///
/// `T` is `f32` (the wire format) or `f64`; everything is converted to `f64` while reading.
///
/// An optional mask of the same shape flags **missing** samples (`true` = missing, e.g. an
/// occluded marker: set its three channels). A frame with any missing sample is left out of every
/// statistic (mean, covariance, ICA): the report counts `frames_used` of `frames_total`, and
/// [`crate::fit::FitOutput::used_frames`] lists them. The value behind a missing flag is never
/// read, so it may be NaN. A channel missing in *every* frame cannot exclude all frames: it is
/// treated as dead (reported in `dead_channels`, mean 0, no loading).
///
/// A present sample that is NaN or infinite is an error, not silently dropped.
#[derive(Debug, Clone, Copy)]
pub struct FitData<'a, T = f32> {
    samples: &'a [T],
    channels: usize,
    missing: Option<&'a [bool]>,
}

impl<'a, T: Copy + Into<f64>> FitData<'a, T> {
    /// Wraps `samples` (`frames x channels`, row-major) with no missing samples.
    ///
    /// # Errors
    /// [`FitError::NoChannels`] if `channels == 0`, [`FitError::RaggedSamples`] if the length is
    /// not a multiple of `channels`.
    pub fn new(samples: &'a [T], channels: usize) -> Result<Self, FitError> {
        if channels == 0 {
            return Err(FitError::NoChannels);
        }
        if samples.len() % channels != 0 {
            return Err(FitError::RaggedSamples {
                len: samples.len(),
                channels,
            });
        }
        Ok(Self {
            samples,
            channels,
            missing: None,
        })
    }

    /// Adds a mask flagging missing samples (`frames x channels`, row-major, `true` = missing).
    ///
    /// # Errors
    /// [`FitError::MaskLength`] if the mask does not have one flag per sample.
    pub fn with_missing(mut self, missing: &'a [bool]) -> Result<Self, FitError> {
        if missing.len() != self.samples.len() {
            return Err(FitError::MaskLength {
                expected: self.samples.len(),
                got: missing.len(),
            });
        }
        self.missing = Some(missing);
        Ok(self)
    }

    /// Frames `start..end` as data of their own (the mask sliced alike).
    ///
    /// # Panics
    /// If `start > end` or `end > self.frames()`.
    pub fn slice_frames(&self, start: usize, end: usize) -> Self {
        let range = start * self.channels..end * self.channels;
        Self {
            samples: &self.samples[range.clone()],
            channels: self.channels,
            missing: self.missing.map(|m| &m[range]),
        }
    }

    /// Frames in the data.
    pub fn frames(&self) -> usize {
        self.samples.len() / self.channels
    }

    /// Channels per frame.
    pub fn channels(&self) -> usize {
        self.channels
    }

    /// One frame's samples.
    pub(crate) fn frame(&self, frame: usize) -> &'a [T] {
        &self.samples[frame * self.channels..(frame + 1) * self.channels]
    }

    /// Every sample, row-major.
    pub(crate) fn samples(&self) -> &'a [T] {
        self.samples
    }

    /// Whether a missing-sample mask was given.
    pub(crate) fn has_mask(&self) -> bool {
        self.missing.is_some()
    }

    /// One frame's missing flags, `None` when nothing is missing anywhere.
    pub(crate) fn frame_missing(&self, frame: usize) -> Option<&'a [bool]> {
        self.missing
            .map(|m| &m[frame * self.channels..(frame + 1) * self.channels])
    }
}
