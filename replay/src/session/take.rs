//! One `[[take]]` of a session manifest.

use serde::{Deserialize, Serialize};

use super::{FrameOrTime, TakeRange};

/// One take of a session.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SessionTake {
    /// Take file, relative to the manifest (or absolute).
    pub file: String,
    /// Sentence id; takes with the same id say the same thing.
    pub sentence: String,
    /// Emotion name.
    pub emotion: String,
    /// First frame used (`240`, or `"2.5s"` from the take's first frame); the take's first
    /// without it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start: Option<FrameOrTime>,
    /// Last frame used, inclusive, likewise; the take's last without it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub end: Option<FrameOrTime>,
}

impl SessionTake {
    /// A take used whole.
    pub fn whole(file: String, sentence: String, emotion: String) -> SessionTake {
        SessionTake {
            file,
            sentence,
            emotion,
            start: None,
            end: None,
        }
    }

    /// The part of the take the session uses.
    pub fn range(&self) -> TakeRange {
        TakeRange {
            start: self.start,
            end: self.end,
        }
    }
}
