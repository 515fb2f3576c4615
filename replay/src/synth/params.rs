//! The generator's knobs and their checks.

use super::{
    EmotionPoint, Layout, SourceLayout, SynthError, Variation, DEFAULT_EMOTIONS,
    DEFAULT_EMOTION_DIMS, DEFAULT_RATE_HZ, DEFAULT_SENTENCES, MAX_RATE_HZ, MAX_SENTENCES,
};

/// The generator's knobs (exactly those of `emoshift synth`).
#[derive(Debug, Clone, PartialEq)]
pub struct SynthParams {
    /// Session seed.
    pub seed: u64,
    /// Number of sentences; every sentence is rendered in every emotion.
    pub sentences: usize,
    /// Emotion names (non-empty, unique, letters/digits/`-`/`_`).
    pub emotions: Vec<String>,
    /// Number of emotion directions (columns of the mixing matrix), 1 to
    /// [`MAX_EMOTION_DIMS`](super::MAX_EMOTION_DIMS).
    pub emotion_dims: usize,
    /// Explicit points for some of the emotions (each with `emotion_dims` coordinates); the
    /// others get their known or spare points ([`space`](super::space)).
    pub emotion_points: Vec<EmotionPoint>,
    /// Frame rate, Hz.
    pub rate_hz: f64,
    /// Whether to add small rigid head motion.
    pub head_motion: bool,
    /// The face layout: markers, names, rigid markers, placement.
    pub layout: Layout,
    /// Session variants the method was not built around ([`variation`](super::variation));
    /// the default is none.
    pub variation: Variation,
}

impl Default for SynthParams {
    fn default() -> SynthParams {
        SynthParams {
            seed: 0,
            sentences: DEFAULT_SENTENCES,
            emotions: DEFAULT_EMOTIONS.iter().map(|s| s.to_string()).collect(),
            emotion_dims: DEFAULT_EMOTION_DIMS,
            emotion_points: Vec::new(),
            rate_hz: DEFAULT_RATE_HZ,
            head_motion: false,
            layout: Layout::default(),
            variation: Variation::default(),
        }
    }
}

impl SynthParams {
    /// Checks the knobs.
    ///
    /// # Errors
    /// The first bad knob: rate, sentence count, emotion list, emotion directions, explicit
    /// points.
    pub fn validate(&self) -> Result<(), SynthError> {
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0 && self.rate_hz <= MAX_RATE_HZ) {
            return Err(SynthError::BadRate(self.rate_hz));
        }
        if self.sentences == 0 {
            return Err(SynthError::NoSentences);
        }
        if self.sentences > MAX_SENTENCES {
            return Err(SynthError::TooManySentences(self.sentences));
        }
        self.validate_emotions()?;
        SourceLayout::new(self.emotion_dims)?;
        self.validate_points()?;
        self.variation.validate(&self.emotions, self.sentences)
    }

    fn validate_emotions(&self) -> Result<(), SynthError> {
        if self.emotions.is_empty() {
            return Err(SynthError::NoEmotions);
        }
        for (i, e) in self.emotions.iter().enumerate() {
            let safe = e
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
            if e.is_empty() || !safe {
                return Err(SynthError::BadEmotionName(e.clone()));
            }
            if self.emotions[..i].contains(e) {
                return Err(SynthError::DuplicateEmotion(e.clone()));
            }
        }
        Ok(())
    }

    fn validate_points(&self) -> Result<(), SynthError> {
        for (i, p) in self.emotion_points.iter().enumerate() {
            if !self.emotions.contains(&p.name) {
                return Err(SynthError::UnlistedPoint(p.name.clone()));
            }
            if self.emotion_points[..i].iter().any(|q| q.name == p.name) {
                return Err(SynthError::DuplicatePoint(p.name.clone()));
            }
            if p.point.len() != self.emotion_dims {
                return Err(SynthError::PointDims {
                    emotion: p.name.clone(),
                    expected: self.emotion_dims,
                    got: p.point.len(),
                });
            }
            if let Some(&value) = p.point.iter().find(|v| !v.is_finite()) {
                return Err(SynthError::NonFinitePoint {
                    emotion: p.name.clone(),
                    value,
                });
            }
        }
        Ok(())
    }
}
