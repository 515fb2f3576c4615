//! The passes of a streaming fit over its data (see [`crate::fit::StreamFit`]).

use std::fmt;

/// The pass a streaming fit needs next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pass {
    /// Raw frames into [`crate::whiten::Moments`].
    Moments,
    /// Raw frames whitened, kept for the later passes and subsampled for the restarts.
    Whiten,
    /// Whitened frames into an [`crate::fastica::UpdateAccumulator`]: one FastICA iteration.
    Update,
    /// Whitened frames into [`crate::fastica::SourceMoments`]: negentropy and skewness of the result.
    Sources,
    /// Nothing left to read: [`crate::fit::StreamFit::finish`].
    Done,
}

impl fmt::Display for Pass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Pass::Moments => "statistics",
            Pass::Whiten => "whitening",
            Pass::Update => "update",
            Pass::Sources => "sources",
            Pass::Done => "final",
        })
    }
}
