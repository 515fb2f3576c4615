//! Why the generator cannot run: [`SynthError`].

use std::path::PathBuf;

/// Why the generator cannot run.
#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    /// The frame rate is not positive and finite, or past [`super::MAX_RATE_HZ`].
    #[error("rate must be above 0 and at most {max} Hz, got {0}", max = super::MAX_RATE_HZ)]
    BadRate(f64),
    /// No sentences were requested.
    #[error("need at least one sentence, got 0")]
    NoSentences,
    /// More sentences than [`super::MAX_SENTENCES`].
    #[error("at most {max} sentences (about 26 hours of takes), got {0}", max = super::MAX_SENTENCES)]
    TooManySentences(usize),
    /// No emotions were given.
    #[error("need at least one emotion")]
    NoEmotions,
    /// An emotion name is empty or unusable in a file name.
    #[error("emotion name {0:?} must be non-empty and use only letters, digits, '-' or '_'")]
    BadEmotionName(String),
    /// An emotion is listed twice.
    #[error("emotion {0:?} is listed twice")]
    DuplicateEmotion(String),
    /// An emotion not in the session was asked for.
    #[error("unknown emotion {0:?}")]
    UnknownEmotion(String),
    /// The emotion space has too few or too many directions.
    #[error("emotion space must have 1 to {max} directions, got {dims}")]
    EmotionDims {
        /// Directions asked for.
        dims: usize,
        /// Emotion fields the generator defines.
        max: usize,
    },
    /// An explicit emotion point does not parse.
    #[error("emotion point {text:?} must be name=x[,y[,z]] with finite numbers")]
    PointSyntax {
        /// The text given.
        text: String,
    },
    /// An explicit point whose coordinate count is not the number of emotion directions.
    #[error(
        "point of emotion {emotion:?} has {got} coordinates, the emotion space has {expected}"
    )]
    PointDims {
        /// Emotion name.
        emotion: String,
        /// Emotion directions.
        expected: usize,
        /// Coordinates given.
        got: usize,
    },
    /// An explicit point with a NaN or infinite coordinate.
    #[error("point of emotion {emotion:?} has a non-finite coordinate {value}")]
    NonFinitePoint {
        /// Emotion name.
        emotion: String,
        /// The bad coordinate.
        value: f64,
    },
    /// An explicit point for a name that is not in the emotion list.
    #[error("point given for emotion {0:?}, which is not in the emotion list")]
    UnlistedPoint(String),
    /// Two explicit points for the same emotion.
    #[error("emotion {0:?} is given two points")]
    DuplicatePoint(String),
    /// A `name=value` item of a variant knob does not parse.
    #[error("{text:?} must be name=number, e.g. angry=3")]
    NameValueSyntax {
        /// The text given.
        text: String,
    },
    /// A variant knob out of its range.
    #[error("{knob} {value} is out of range: expected {expected}")]
    BadVariation {
        /// The knob.
        knob: &'static str,
        /// The value given.
        value: f64,
        /// What it accepts.
        expected: String,
    },
    /// A variant knob names an emotion the session does not have.
    #[error("{knob} names emotion {emotion:?}, which is not in the emotion list ({known}): add it to the emotions or fix the name")]
    UnlistedVariation {
        /// The knob.
        knob: &'static str,
        /// The emotion named.
        emotion: String,
        /// The session's emotions, comma separated.
        known: String,
    },
    /// A variant knob given twice for one emotion.
    #[error("{knob} is given twice for emotion {emotion:?}")]
    RepeatedVariation {
        /// The knob.
        knob: &'static str,
        /// The emotion.
        emotion: String,
    },
    /// A take's level vector does not have one level per emotion direction.
    #[error("take levels have {got} coordinates, the emotion space has {expected}")]
    LevelDims {
        /// Emotion directions.
        expected: usize,
        /// Levels given.
        got: usize,
    },
    /// A take's level vector holds a NaN or infinite level.
    #[error("take level {0} is not finite")]
    NonFiniteLevel(f64),
    /// A sentence index beyond the corpus.
    #[error("sentence index {sentence} out of range (session has {count})")]
    SentenceOutOfRange {
        /// The index asked for.
        sentence: usize,
        /// Number of sentences.
        count: usize,
    },
    /// A warp that does not span its sentence.
    #[error(
        "warp spans {warp_s} s of canonical time but sentence {sentence} lasts {sentence_s} s"
    )]
    WarpMismatch {
        /// Sentence id.
        sentence: String,
        /// Canonical duration covered by the warp.
        warp_s: f64,
        /// Canonical duration of the sentence.
        sentence_s: f64,
    },
    /// A rendered take broke a take invariant (a bug, reported rather than panicking).
    #[error(transparent)]
    Take(#[from] crate::TakeError),
    /// Writing a take file failed.
    #[error("cannot write take {path:?}")]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        source: crate::WriteError,
    },
    /// A file or folder could not be read or written.
    #[error("cannot access {path:?}")]
    Io {
        /// The path.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// A truth file is not valid JSON for its type.
    #[error("bad truth json {path:?}")]
    Json {
        /// The file.
        path: PathBuf,
        /// The JSON error.
        source: serde_json::Error,
    },
    /// The manifest or region map is invalid.
    #[error(transparent)]
    Session(#[from] crate::session::SessionError),
}
