//! Which column of the mixing matrix (and of each frame's source vector) holds which source.
//!
//! Column order: the four speech sources, then the `k` emotion sources (`emotion`,
//! `emotion_1`, ...), then `brow_raise`, `blink` and the six head-pose columns. With one emotion
//! direction this is exactly the generator's historic order (speech 0-3, emotion 4,
//! brow_raise 5, blink 6, head 7-12); further emotion directions sit right after column 4, so
//! the emotion columns stay contiguous and the later columns shift by `k - 1`.

use std::ops::Range;

use serde::{Deserialize, Serialize};

use super::speech::{SPEECH_SOURCES, SPEECH_SOURCE_NAMES};
use super::SynthError;

/// Largest number of emotion directions: one per emotion field of the mixing matrix
/// (smile/frown, brow knit + lip press, inner brow raise + mouth corners down).
pub const MAX_EMOTION_DIMS: usize = 3;
/// Number of head-pose columns (pitch, yaw, roll in rad; tx, ty, tz in mm).
pub const HEAD_COLUMNS: usize = 6;
/// Names of the head-pose sources, in column order.
const HEAD_NAMES: [&str; HEAD_COLUMNS] = [
    "head_pitch",
    "head_yaw",
    "head_roll",
    "head_tx",
    "head_ty",
    "head_tz",
];

/// Name and role of a source.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct SourceInfo {
    /// Source name, e.g. `jaw_open`.
    pub name: String,
    /// Role: `speech`, `emotion`, `eyebrows`, `eyelids` or `head`.
    pub role: String,
}

/// The column layout of a generator with `emotion_dims` emotion directions.
///
/// ```
/// use replay::synth::SourceLayout;
/// let one = SourceLayout::new(1)?;
/// assert_eq!((one.emotion(0), one.brow_raise(), one.blink(), one.head(), one.count()), (4, 5, 6, 7, 13));
/// let three = SourceLayout::new(3)?;
/// assert_eq!(three.emotions(), 4..7);
/// assert_eq!((three.brow_raise(), three.head(), three.count()), (7, 9, 15));
/// # Ok::<(), replay::synth::SynthError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SourceLayout {
    emotion_dims: usize,
}

impl Default for SourceLayout {
    /// One emotion direction: the historic 13 columns.
    fn default() -> SourceLayout {
        SourceLayout { emotion_dims: 1 }
    }
}

impl SourceLayout {
    /// The layout with `emotion_dims` emotion columns.
    ///
    /// # Errors
    /// [`SynthError::EmotionDims`] unless `1 <= emotion_dims <= MAX_EMOTION_DIMS`.
    pub fn new(emotion_dims: usize) -> Result<SourceLayout, SynthError> {
        if (1..=MAX_EMOTION_DIMS).contains(&emotion_dims) {
            Ok(SourceLayout { emotion_dims })
        } else {
            Err(SynthError::EmotionDims {
                dims: emotion_dims,
                max: MAX_EMOTION_DIMS,
            })
        }
    }

    /// Number of emotion directions.
    pub fn emotion_dims(self) -> usize {
        self.emotion_dims
    }

    /// Number of speech columns (the first columns).
    pub fn speech_count(self) -> usize {
        SPEECH_SOURCES
    }

    /// Column of emotion direction `i` (`0 <= i < emotion_dims`).
    ///
    /// # Panics
    /// If `i` is not below [`SourceLayout::emotion_dims`] (a caller bug).
    pub fn emotion(self, i: usize) -> usize {
        assert!(i < self.emotion_dims, "emotion direction {i} out of range");
        SPEECH_SOURCES + i
    }

    /// The emotion columns.
    pub fn emotions(self) -> Range<usize> {
        SPEECH_SOURCES..SPEECH_SOURCES + self.emotion_dims
    }

    /// Column of the eyebrow-emphasis source.
    pub fn brow_raise(self) -> usize {
        SPEECH_SOURCES + self.emotion_dims
    }

    /// Column of the blink source.
    pub fn blink(self) -> usize {
        self.brow_raise() + 1
    }

    /// First of the six head-pose columns; every facial column comes before it.
    pub fn head(self) -> usize {
        self.blink() + 1
    }

    /// Number of columns.
    pub fn count(self) -> usize {
        self.head() + HEAD_COLUMNS
    }

    /// Name of the source of emotion direction `i`: `emotion`, `emotion_1`, `emotion_2`.
    pub fn emotion_name(i: usize) -> String {
        if i == 0 {
            "emotion".to_string()
        } else {
            format!("emotion_{i}")
        }
    }

    /// Every source, in column order, with its name and role.
    pub fn source_infos(self) -> Vec<SourceInfo> {
        let info = |name: String, role: &str| SourceInfo {
            name,
            role: role.to_string(),
        };
        let mut v: Vec<SourceInfo> = SPEECH_SOURCE_NAMES
            .iter()
            .map(|n| info(n.to_string(), "speech"))
            .collect();
        v.extend((0..self.emotion_dims).map(|i| info(Self::emotion_name(i), "emotion")));
        v.push(info("brow_raise".into(), "eyebrows"));
        v.push(info("blink".into(), "eyelids"));
        v.extend(HEAD_NAMES.iter().map(|n| info(n.to_string(), "head")));
        v
    }
}

#[cfg(test)]
mod tests;
