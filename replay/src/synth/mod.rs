//! A deterministic synthetic talking face with known sources, for testing the emotion method.
//!
//! A [`Synth`] holds a 109-marker face ([`geometry`]), a corpus of sentences ([`speech`]), the
//! emotion space (each emotion a point on `k` emotion directions, [`space`]) and the true linear
//! mixing matrix ([`mixing`], columns in [`SourceLayout`] order, emotion fields in
//! [`expressions`]). Each take is sentence x emotion with its own smooth timing warp ([`warp`]);
//! rendering ([`render`]) mixes the sources onto the rest face, applies optional rigid head
//! motion and 0.2 mm noise. The ground truth ([`truth`]) travels beside the takes as JSON.
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
//! Two or three emotion directions, and a blend rendered at the timing of a real take:
//!
//! ```
//! use replay::synth::{EmotionPoint, Synth, SynthParams};
//! let synth = Synth::new(SynthParams {
//!     sentences: 1,
//!     emotion_dims: 2,
//!     emotions: vec!["neutral".into(), "sad".into(), "angry".into(), "calm".into()],
//!     emotion_points: vec!["calm=0.3,-0.4".parse::<EmotionPoint>()?],
//!     ..SynthParams::default()
//! })?;
//! assert_eq!(synth.point_of("sad")?, &[-0.6, -0.8]);
//! let neutral = synth.take_spec(0, "neutral")?;
//! let blend = synth.blend(&[("sad", 0.5), ("angry", 0.5)])?;
//! let blended = synth.render_take(&neutral.clone().with_levels(blend))?;
//! assert_eq!(blended.take.n_frames(), synth.render_take(&neutral)?.take.n_frames());
//! # Ok::<(), replay::synth::SynthError>(())
//! ```
//!
//! Same parameters, same bits: every random draw comes from its own seeded ChaCha8 stream, and
//! with one emotion direction the sessions are those of the one-source generator, bit for bit.

pub mod columns;
mod error;
pub mod expressions;
pub mod geometry;
pub mod layout;
pub mod mixing;
mod params;
pub mod render;
mod seeds;
pub mod session_io;
mod shapes;
pub mod sources;
pub mod space;
pub mod speech;
pub mod spread;
pub mod truth;
pub mod variation;
pub mod warp;

pub use columns::{SourceInfo, SourceLayout, MAX_EMOTION_DIMS};
pub use error::SynthError;
pub use geometry::{FaceGeometry, Region};
pub use layout::{Layout, MarkerSet, Naming, RigidMarkers};
pub use params::SynthParams;
pub use render::{RenderedTake, TakeSpec, NOISE_STD_MM};
pub use session_io::{generate_session, write_session, SessionSummary, SynthSession};
pub use space::EmotionPoint;
pub use speech::Sentence;
pub use truth::{load_truth, MixingTruth, SessionTruth, TakeTruth};
pub use variation::{NameValue, Variation};
pub use warp::Warp;

use seeds::{name_key, sub_rng, sub_seed, Stream};

/// Default frame rate, Hz.
pub const DEFAULT_RATE_HZ: f64 = 120.0;
/// Default number of sentences.
pub const DEFAULT_SENTENCES: usize = 8;
/// Most sentences: 10,000 sentences in three emotions are about 26 hours at 120 Hz (the
/// 4-hour benchmark session has 1,504). Past it the sentences alone would fill memory
/// before a take is written.
pub const MAX_SENTENCES: usize = 10_000;
/// Highest frame rate, Hz: past what facial capture runs at (optical systems to about 1 kHz).
/// A take's frames are rendered in memory, so a rate of 1e7 Hz would ask for tens of GB.
pub const MAX_RATE_HZ: f64 = 2_000.0;
/// Default emotions.
pub const DEFAULT_EMOTIONS: [&str; 3] = ["neutral", "happy", "frustrated"];
/// Default number of emotion directions: one, the smile/frown line.
pub const DEFAULT_EMOTION_DIMS: usize = 1;

/// A configured generator: face, sentences, emotion points and mixing matrix.
#[derive(Debug, Clone)]
pub struct Synth {
    params: SynthParams,
    columns: SourceLayout,
    face: FaceGeometry,
    rest: Vec<f64>,
    mixing: Vec<f64>,
    sentences: Vec<Sentence>,
    points: Vec<Vec<f64>>,
    /// Per emotion (list order), whether it is spoken in each sentence.
    spoken: Vec<Vec<bool>>,
}

impl Synth {
    /// Validates the parameters and builds the face, sentences and mixing matrix.
    ///
    /// # Errors
    /// [`SynthParams::validate`] failures.
    pub fn new(params: SynthParams) -> Result<Synth, SynthError> {
        params.validate()?;
        let columns = SourceLayout::new(params.emotion_dims)?;
        let face = params.layout.face(params.seed);
        let sentences = (0..params.sentences)
            .map(|i| Sentence::generate(params.seed, i, params.sentences))
            .collect();
        let mut mixing = mixing::mixing_matrix(&face, params.layout.soft_nose(), columns);
        let v = &params.variation;
        if v.spread_effects > 0.0 {
            spread::add_spread_effects(&mut mixing, &face, columns, params.seed, v.spread_effects);
        }
        let spoken = params
            .emotions
            .iter()
            .map(|e| variation::spoken_in(params.seed, e, v.takes_of(e), params.sentences))
            .collect();
        Ok(Synth {
            rest: face.rest_flat(),
            mixing,
            spoken,
            points: space::emotion_points(
                &params.emotions,
                params.emotion_dims,
                &params.emotion_points,
            ),
            columns,
            face,
            sentences,
            params,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &SynthParams {
        &self.params
    }

    /// Which column holds which source.
    pub fn source_layout(&self) -> SourceLayout {
        self.columns
    }

    /// The marker set.
    pub fn face(&self) -> &FaceGeometry {
        &self.face
    }

    /// Rest shape, channels (markers x 3), mm.
    pub fn rest(&self) -> &[f64] {
        &self.rest
    }

    /// Mixing matrix, channels x [`SourceLayout::count`], row-major, mm per source unit.
    pub fn mixing(&self) -> &[f64] {
        &self.mixing
    }

    /// The sentences.
    pub fn sentences(&self) -> &[Sentence] {
        &self.sentences
    }

    /// Base level of an emotion on the first emotion direction (its whole level with one
    /// direction).
    ///
    /// # Errors
    /// [`SynthError::UnknownEmotion`].
    pub fn level_of(&self, emotion: &str) -> Result<f64, SynthError> {
        Ok(self.point_of(emotion)?[0])
    }

    /// Base point of an emotion: its level on each emotion direction, before the per-sentence
    /// intensity.
    ///
    /// # Errors
    /// [`SynthError::UnknownEmotion`].
    pub fn point_of(&self, emotion: &str) -> Result<&[f64], SynthError> {
        let i = self.emotion_index(emotion)?;
        Ok(&self.points[i])
    }

    /// The level vector of a blend of this session's emotions, `Σ weight · point`; e.g.
    /// `[("sad", 0.5), ("angry", 0.5)]`. Render it with [`TakeSpec::with_levels`].
    ///
    /// # Errors
    /// [`SynthError::UnknownEmotion`] for a name not in the session.
    pub fn blend(&self, weights: &[(&str, f64)]) -> Result<Vec<f64>, SynthError> {
        let parts = weights
            .iter()
            .map(|(name, w)| Ok((self.point_of(name)?, *w)))
            .collect::<Result<Vec<_>, SynthError>>()?;
        Ok(space::blend(self.columns.emotion_dims(), parts)
            .expect("every point of the session has one level per direction"))
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

    /// Whether the session has a take of `sentence` in `emotion` (every sentence is spoken in
    /// every emotion unless [`Variation::takes`] says otherwise).
    pub fn spoken(&self, sentence: usize, emotion: &str) -> bool {
        self.emotion_index(emotion)
            .ok()
            .and_then(|e| self.spoken[e].get(sentence).copied())
            .unwrap_or(false)
    }

    /// The session's takes, sentence-major: (sentence, emotion).
    pub fn takes(&self) -> Vec<(usize, &str)> {
        (0..self.sentences.len())
            .flat_map(|s| {
                self.params
                    .emotions
                    .iter()
                    .enumerate()
                    .filter(move |(e, _)| self.spoken[*e][s])
                    .map(move |(_, e)| (s, e.as_str()))
            })
            .collect()
    }

    /// The take of `sentence` in `emotion`: its levels (base point x per-take intensity, plus
    /// the emotion x sentence offset of a [`Variation`]), its own random warp (at the emotion's
    /// speech rate) and its own seed. Defined for every sentence and emotion, spoken in the
    /// session or not.
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
        let point = self.point_of(emotion)?;
        let v = &self.params.variation;
        let seed = self.params.seed;
        let intensity = if v.take_intensity > 0.0 {
            variation::take_intensity(seed, sentence, emotion, v.take_intensity)
        } else {
            sources::sentence_intensity(seed, sentence, emotion)
        };
        let mut emotion_levels: Vec<f64> = point.iter().map(|p| p * intensity).collect();
        if v.interaction > 0.0 {
            let offset =
                variation::interaction(seed, sentence, emotion, point.len(), v.interaction);
            for (l, o) in emotion_levels.iter_mut().zip(offset) {
                *l += o;
            }
        }
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
            emotion_levels,
            warp: Warp::random_paced(
                &mut rng,
                s.duration_s,
                self.params.rate_hz,
                v.rate_of(emotion),
            ),
            seed,
            noise: true,
        })
    }

    /// The truth of editing the take `spec` to emotion `target`: the same performance (timing,
    /// drift, blinks, head motion, noise) at the levels `target` would have. With a per-take
    /// intensity ([`Variation::take_intensity`]) those are the levels of `target`'s average
    /// take in the session ([`Synth::mean_levels`]): the edit must remove the take's own
    /// intensity and cannot know a target take's. Otherwise they are `target`'s own take of
    /// the sentence, as [`TakeSpec::with_timing_of`] renders it.
    ///
    /// # Errors
    /// As [`Synth::take_spec`].
    pub fn counterfactual(&self, spec: &TakeSpec, target: &str) -> Result<TakeSpec, SynthError> {
        let mut truth = self.take_spec(spec.sentence, target)?.with_timing_of(spec);
        if self.params.variation.take_intensity > 0.0 {
            truth.emotion_levels = self.mean_levels(target)?;
        }
        Ok(truth)
    }

    /// The mean levels of the session's takes in `emotion`: where its average take sits.
    ///
    /// # Errors
    /// [`SynthError::UnknownEmotion`].
    pub fn mean_levels(&self, emotion: &str) -> Result<Vec<f64>, SynthError> {
        let dims = self.columns.emotion_dims();
        let mut sum = vec![0.0; dims];
        let mut count = 0usize;
        for s in (0..self.sentences.len()).filter(|&s| self.spoken(s, emotion)) {
            for (acc, l) in sum
                .iter_mut()
                .zip(self.take_spec(s, emotion)?.emotion_levels)
            {
                *acc += l;
            }
            count += 1;
        }
        if count == 0 {
            return Ok(self.point_of(emotion)?.to_vec());
        }
        Ok(sum.into_iter().map(|v| v / count as f64).collect())
    }

    /// Renders a take.
    ///
    /// # Errors
    /// [`SynthError::SentenceOutOfRange`], [`SynthError::WarpMismatch`], or
    /// [`SynthError::LevelDims`] / [`SynthError::NonFiniteLevel`] for a level vector that is
    /// not one finite level per emotion direction.
    pub fn render_take(&self, spec: &TakeSpec) -> Result<RenderedTake, SynthError> {
        render::render(self, spec)
    }

    /// Every take of the session ([`Synth::takes`]), sentence-major (s01 in each emotion, then
    /// s02, ...).
    ///
    /// # Errors
    /// As [`Synth::render_take`] (not expected for specs from [`Synth::take_spec`]).
    pub fn render_all(&self) -> Result<Vec<RenderedTake>, SynthError> {
        self.takes()
            .into_iter()
            .map(|(s, e)| self.render_take(&self.take_spec(s, e)?))
            .collect()
    }
}
