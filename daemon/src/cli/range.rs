//! `--start`/`--end`: a frame or time range of a take, the same flags for `convert` and `edit`.

use clap::Args;

use crate::offline::trim::FrameOrTime;

/// A frame or time range: both ends inclusive, either left out for the take's own.
#[derive(Debug, Clone, Copy, Default, Args)]
pub struct RangeArgs {
    /// First frame kept: a frame number as the file numbers it (240) or seconds from the
    /// take's start (2.5s) [default: the first].
    #[arg(long, value_name = "FRAME|SECONDSs")]
    pub start: Option<FrameOrTime>,
    /// Last frame kept, inclusive, likewise [default: the last].
    #[arg(long, value_name = "FRAME|SECONDSs")]
    pub end: Option<FrameOrTime>,
}

impl RangeArgs {
    /// Whether a range was given.
    pub fn is_some(&self) -> bool {
        self.start.is_some() || self.end.is_some()
    }
}
