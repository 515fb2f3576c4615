//! Why a fit was refused.

use thiserror::Error;

use super::Pass;

/// Everything that makes [`crate::fit::FastIcaParams::fit`] refuse its input or parameters.
///
/// Numerical non-convergence is *not* an error: it is reported per restart in
/// [`crate::TrainReport`], because a slightly unconverged ICA is still usable and the caller
/// decides.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum FitError {
    /// The data has no channels.
    #[error("data has no channels")]
    NoChannels,
    /// The sample slice is not a whole number of frames.
    #[error("{len} samples are not a whole number of frames of {channels} channels")]
    RaggedSamples {
        /// Length of the sample slice.
        len: usize,
        /// Channels per frame.
        channels: usize,
    },
    /// The missing-sample mask does not have one flag per sample.
    #[error("missing-sample mask has {got} flags, expected {expected} (frames x channels)")]
    MaskLength {
        /// Samples in the data.
        expected: usize,
        /// Flags in the mask.
        got: usize,
    },
    /// A sample marked present is NaN or infinite.
    #[error("sample at frame {frame}, channel {channel} is not finite ({value})")]
    NonFinite {
        /// Frame index.
        frame: usize,
        /// Channel index.
        channel: usize,
        /// The offending value.
        value: f64,
    },
    /// Too few complete frames to estimate the statistics.
    #[error("only {used} of {total} frames are complete, at least {needed} are needed")]
    TooFewFrames {
        /// Frames without missing samples.
        used: usize,
        /// Frames offered.
        total: usize,
        /// Frames required.
        needed: usize,
    },
    /// Every channel is constant or missing.
    #[error("all {channels} channels are constant or missing")]
    NoVariance {
        /// Channels offered.
        channels: usize,
    },
    /// The covariance's eigendecomposition did not converge (a covariance of finite values
    /// does not do this).
    #[error("the covariance's eigendecomposition did not converge")]
    Eigendecomposition,
    /// A fixed component count of zero.
    #[error("component count must be at least 1, got 0")]
    ZeroComponents,
    /// A fixed component count above the rank of the data.
    #[error("m = {m} is larger than the data's rank ({rank})")]
    ComponentsExceedRank {
        /// Requested components.
        m: usize,
        /// Numerical rank of the covariance of the complete frames.
        rank: usize,
    },
    /// A variance target outside the accepted range.
    #[error("variance target {target} is outside [{min}, {max}]")]
    VarianceTarget {
        /// The target given.
        target: f64,
        /// Smallest accepted target.
        min: f64,
        /// Largest accepted target.
        max: f64,
    },
    /// A tolerance that is not a positive finite number.
    #[error("tolerance must be positive and finite, got {tol}")]
    Tolerance {
        /// The tolerance given.
        tol: f64,
    },
    /// An iteration cap of zero.
    #[error("max_iter must be at least 1, got 0")]
    ZeroIterations,
    /// A restart count of zero.
    #[error("restarts must be at least 1, got 0")]
    ZeroRestarts,
    /// A chunk or partial accumulator of another width than the fit's.
    #[error("expected frames of {expected} values, got {got}")]
    ChannelMismatch {
        /// Values per frame the fit was set up for.
        expected: usize,
        /// Values per frame given.
        got: usize,
    },
    /// A streaming pass saw another number of used frames than the statistics pass: the chunk
    /// source did not give the same frames on every pass.
    #[error("the {pass} pass saw {got} used frames, the statistics pass counted {expected}")]
    FrameCountMismatch {
        /// The pass that disagreed.
        pass: Pass,
        /// Used frames counted by the statistics pass.
        expected: usize,
        /// Used frames this pass saw.
        got: usize,
    },
    /// A streaming pass's result was handed in when another pass was due.
    #[error("the {expected} pass is due, got the result of a {got} pass")]
    UnexpectedPass {
        /// The pass that is due.
        expected: Pass,
        /// The pass whose result was given.
        got: Pass,
    },
    /// A FastICA accumulator made for another rotation or iteration than the one it was
    /// handed to (a stale result from an earlier pass, or partials of different passes merged).
    #[error("accumulator was made for another rotation or iteration")]
    AccumulatorMismatch,
}
