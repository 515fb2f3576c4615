//! A deterministic synthetic talking face with known sources, for testing the emotion method.
//!
//! A [`Synth`] holds a 109-marker face ([`geometry`]), a corpus of sentences ([`speech`]), the
//! emotion levels ([`sources`]) and the true linear mixing matrix ([`mixing`]). Each take is
//! sentence x emotion with its own smooth timing warp ([`warp`]); rendering ([`render`]) mixes
//! the sources onto the rest face, applies optional rigid head motion and 0.2 mm noise. The
//! ground truth ([`truth`]) travels beside the takes as JSON.
//!
//! ```
//! use replay::synth::{Synth, SynthParams};
//! let synth = Synth::new(SynthParams { sentences: 1, ..SynthParams::default() })?;
//! let frustrated = synth.take_spec(0, "frustrated")?;
//! let happy_same_timing = synth.take_spec(0, "happy")?.with_timing_of(&frustrated);
//! let a = synth.render_take(&frustrated)?;
//! let b = synth.render_take(&happy_same_timing)?;
//! assert_eq!(a.take.n_frames(), b.take.n_frames());
//! # Ok::<(), replay::synth::SynthError>(())
//! ```
//!
//! Same parameters, same bits: every random draw comes from its own seeded ChaCha8 stream.

pub mod geometry;
pub mod layout;
pub mod mixing;
pub mod render;
mod seeds;
pub mod session_io;
pub mod sources;
pub mod speech;
pub mod truth;
pub mod warp;

use std::path::PathBuf;

pub use geometry::{FaceGeometry, Region};
pub use layout::{Layout, MarkerSet, Naming, RigidMarkers};
pub use mixing::{SourceInfo, SOURCE_COUNT};
pub use render::{RenderedTake, TakeSpec, NOISE_STD_MM};
pub use session_io::{generate_session, write_session, SessionSummary, SynthSession};
pub use speech::Sentence;
pub use truth::{load_truth, MixingTruth, SessionTruth, TakeTruth};
pub use warp::Warp;

use seeds::{name_key, sub_rng, sub_seed, Stream};

/// Default frame rate, Hz.
pub const DEFAULT_RATE_HZ: f64 = 120.0;
/// Default number of sentences.
pub const DEFAULT_SENTENCES: usize = 8;
/// Default emotions.
pub const DEFAULT_EMOTIONS: [&str; 3] = ["neutral", "happy", "frustrated"];

/// Why the generator cannot run.
#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    /// The frame rate is not positive and finite.
    #[error("rate must be positive and finite, got {0}")]
    BadRate(f64),
    /// No sentences were requested.
    #[error("need at least one sentence, got 0")]
    NoSentences,
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
    #[error("cannot write take {path:?}: {source}")]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        source: crate::WriteError,
    },
    /// A file or folder could not be read or written.
    #[error("cannot access {path:?}: {source}")]
    Io {
        /// The path.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// A truth file is not valid JSON for its type.
    #[error("bad truth json {path:?}: {source}")]
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

/// The generator's knobs (exactly those of `emoshift synth`).
#[derive(Debug, Clone, PartialEq)]
pub struct SynthParams {
    /// Session seed.
    pub seed: u64,
    /// Number of sentences; every sentence is rendered in every emotion.
    pub sentences: usize,
    /// Emotion names (non-empty, unique, letters/digits/`-`/`_`).
    pub emotions: Vec<String>,
    /// Frame rate, Hz.
    pub rate_hz: f64,
    /// Whether to add small rigid head motion.
    pub head_motion: bool,
    /// The face layout: markers, names, rigid markers, placement.
    pub layout: Layout,
}

impl Default for SynthParams {
    fn default() -> SynthParams {
        SynthParams {
            seed: 0,
            sentences: DEFAULT_SENTENCES,
            emotions: DEFAULT_EMOTIONS.iter().map(|s| s.to_string()).collect(),
            rate_hz: DEFAULT_RATE_HZ,
            head_motion: false,
            layout: Layout::default(),
        }
    }
}

impl SynthParams {
    /// Checks the knobs.
    ///
    /// # Errors
    /// The first bad knob: rate, sentence count, emotion list.
    pub fn validate(&self) -> Result<(), SynthError> {
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0) {
            return Err(SynthError::BadRate(self.rate_hz));
        }
        if self.sentences == 0 {
            return Err(SynthError::NoSentences);
        }
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
}

/// A configured generator: face, sentences, emotion levels and mixing matrix.
#[derive(Debug, Clone)]
pub struct Synth {
    params: SynthParams,
    face: FaceGeometry,
    rest: Vec<f64>,
    mixing: Vec<f64>,
    sentences: Vec<Sentence>,
    levels: Vec<f64>,
}

impl Synth {
    /// Validates the parameters and builds the face, sentences and mixing matrix.
    ///
    /// # Errors
    /// [`SynthParams::validate`] failures.
    pub fn new(params: SynthParams) -> Result<Synth, SynthError> {
        params.validate()?;
        let face = params.layout.face(params.seed);
        let sentences = (0..params.sentences)
            .map(|i| Sentence::generate(params.seed, i, params.sentences))
            .collect();
        Ok(Synth {
            rest: face.rest_flat(),
            mixing: mixing::mixing_matrix(&face, params.layout.soft_nose()),
            levels: sources::emotion_levels(&params.emotions),
            face,
            sentences,
            params,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &SynthParams {
        &self.params
    }

    /// The marker set.
    pub fn face(&self) -> &FaceGeometry {
        &self.face
    }

    /// Rest shape, channels (markers x 3), mm.
    pub fn rest(&self) -> &[f64] {
        &self.rest
    }

    /// Mixing matrix, channels x [`SOURCE_COUNT`], row-major, mm per source unit.
    pub fn mixing(&self) -> &[f64] {
        &self.mixing
    }

    /// The sentences.
    pub fn sentences(&self) -> &[Sentence] {
        &self.sentences
    }

    /// Base level of an emotion of this session.
    ///
    /// # Errors
    /// [`SynthError::UnknownEmotion`].
    pub fn level_of(&self, emotion: &str) -> Result<f64, SynthError> {
        let i = self.emotion_index(emotion)?;
        Ok(self.levels[i])
    }

    fn emotion_index(&self, emotion: &str) -> Result<usize, SynthError> {
        self.params
            .emotions
            .iter()
            .position(|e| e == emotion)
            .ok_or_else(|| SynthError::UnknownEmotion(emotion.to_string()))
    }

    /// Name of the take of `sentence` in `emotion`, e.g. `s03_happy`.
    pub fn take_name(&self, sentence: usize, emotion: &str) -> String {
        let id = speech::sentence_id(sentence, self.params.sentences);
        format!("{id}_{emotion}")
    }

    /// The session's take of `sentence` in `emotion`: its level (base x per-sentence
    /// intensity), its own random warp and its own seed.
    ///
    /// # Errors
    /// [`SynthError::SentenceOutOfRange`] or [`SynthError::UnknownEmotion`].
    pub fn take_spec(&self, sentence: usize, emotion: &str) -> Result<TakeSpec, SynthError> {
        let s = self
            .sentences
            .get(sentence)
            .ok_or(SynthError::SentenceOutOfRange {
                sentence,
                count: self.sentences.len(),
            })?;
        let base = self.level_of(emotion)?;
        let seed = sub_seed(
            self.params.seed,
            Stream::Take,
            sentence as u64,
            name_key(emotion),
        );
        let mut rng = sub_rng(seed, Stream::Warp, 0, 0);
        Ok(TakeSpec {
            sentence,
            emotion: emotion.to_string(),
            emotion_level: base * sources::sentence_intensity(self.params.seed, sentence, emotion),
            warp: Warp::random(&mut rng, s.duration_s, self.params.rate_hz),
            seed,
            noise: true,
        })
    }

    /// Renders a take.
    ///
    /// # Errors
    /// [`SynthError::SentenceOutOfRange`] or [`SynthError::WarpMismatch`].
    pub fn render_take(&self, spec: &TakeSpec) -> Result<RenderedTake, SynthError> {
        render::render(self, spec)
    }

    /// Every take of the session, sentence-major (s01 in each emotion, then s02, ...).
    ///
    /// # Errors
    /// As [`Synth::render_take`] (not expected for specs from [`Synth::take_spec`]).
    pub fn render_all(&self) -> Result<Vec<RenderedTake>, SynthError> {
        let mut out = Vec::new();
        for s in 0..self.sentences.len() {
            for e in &self.params.emotions {
                out.push(self.render_take(&self.take_spec(s, e)?)?);
            }
        }
        Ok(out)
    }
}
