//! Ground truth of a synthetic session, kept beside the takes as JSON (`truth/mixing.json`,
//! `truth/<take>.json`) so tests can check what an ICA model recovers.

use std::collections::BTreeMap;
use std::fs;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::columns::SourceInfo;
use super::sources::BlinkEvent;
use super::space::blend;
use super::speech::{BrowEvent, Segment};
use super::SynthError;

/// Folder, under the session folder, holding the truth files.
pub const TRUTH_DIR: &str = "truth";
/// File name of the session-wide truth.
pub const MIXING_FILE: &str = "mixing.json";

/// An emotion and its base point in the emotion space.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EmotionLevel {
    /// Emotion name, e.g. `happy`.
    pub name: String,
    /// Base level on the first emotion direction (before per-sentence intensity): with one
    /// direction neutral 0, happy 1, frustrated -1.
    pub level: f64,
    /// Base level on every emotion direction (empty in truth written before emotion spaces
    /// existed: read it with [`EmotionLevel::point`]).
    #[serde(default)]
    pub point: Vec<f64>,
}

impl EmotionLevel {
    /// The base point; `[level]` for truth written with a single emotion source.
    pub fn point(&self) -> Vec<f64> {
        if self.point.is_empty() {
            vec![self.level]
        } else {
            self.point.clone()
        }
    }
}

/// Session-wide truth: the linear model every take was rendered from.
///
/// Without head motion, each frame is exactly `rest + matrix · sources + noise`. With head
/// motion the rigid transform is applied exactly (to the deformed face) and the six head columns
/// are its small-angle linearisation: the model then misses the second-order terms, measured at
/// a median 0.10 mm and at most 0.56 mm per coordinate over a default session.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MixingTruth {
    /// Marker labels, in take order.
    pub labels: Vec<String>,
    /// Sources (name and role), in column order.
    pub sources: Vec<SourceInfo>,
    /// Mixing matrix, one row per channel (marker * 3 + axis), one column per source, mm per
    /// source unit.
    pub matrix: Vec<Vec<f64>>,
    /// Rest (neutral) shape, one value per channel, mm.
    pub rest: Vec<f64>,
    /// Region name -> marker labels.
    pub regions: BTreeMap<String, Vec<String>>,
    /// Emotions in session order with their base points.
    pub emotions: Vec<EmotionLevel>,
    /// Columns of the emotion directions, in direction order (empty in truth written before
    /// emotion spaces existed: read them with [`MixingTruth::emotion_columns`]).
    #[serde(default)]
    pub emotion_columns: Vec<usize>,
    /// Frame rate of every take.
    pub rate_hz: f64,
    /// Session seed.
    pub seed: u64,
    /// Standard deviation of the sensor noise per coordinate, mm.
    pub noise_std_mm: f64,
    /// Whether rigid head motion was rendered.
    pub head_motion: bool,
    /// The face layout, described (empty in truth written before layouts existed).
    #[serde(default)]
    pub layout: String,
    /// The session's variants, described (`none`; empty in truth written before variants
    /// existed).
    #[serde(default)]
    pub variation: String,
    /// Pivot of the head rotations, mm.
    pub head_pivot: [f64; 3],
}

impl MixingTruth {
    /// Column index of the source called `name`.
    pub fn source_index(&self, name: &str) -> Option<usize> {
        self.sources.iter().position(|s| s.name == name)
    }

    /// Column indices of every source with `role`.
    pub fn role_indices(&self, role: &str) -> Vec<usize> {
        (0..self.sources.len())
            .filter(|&i| self.sources[i].role == role)
            .collect()
    }

    /// One column of the mixing matrix (channels).
    pub fn column(&self, source: usize) -> Vec<f64> {
        self.matrix.iter().map(|row| row[source]).collect()
    }

    /// Base level of an emotion on the first emotion direction.
    pub fn level_of(&self, emotion: &str) -> Option<f64> {
        self.emotions
            .iter()
            .find(|e| e.name == emotion)
            .map(|e| e.level)
    }

    /// Base point of an emotion (one level per emotion direction).
    pub fn point_of(&self, emotion: &str) -> Option<Vec<f64>> {
        self.emotions
            .iter()
            .find(|e| e.name == emotion)
            .map(EmotionLevel::point)
    }

    /// Columns of the emotion directions, in direction order.
    pub fn emotion_columns(&self) -> Vec<usize> {
        if self.emotion_columns.is_empty() {
            self.role_indices("emotion")
        } else {
            self.emotion_columns.clone()
        }
    }

    /// The level vector of a blend, `Σ weight · point`, e.g. `[("sad", 0.5), ("angry", 0.5)]`;
    /// `None` for an emotion not in the session.
    pub fn blend(&self, weights: &[(&str, f64)]) -> Option<Vec<f64>> {
        let points = weights
            .iter()
            .map(|(name, w)| Some((self.point_of(name)?, *w)))
            .collect::<Option<Vec<_>>>()?;
        let dims = self.emotion_columns().len();
        blend(dims, points.iter().map(|(p, w)| (p.as_slice(), *w)))
    }

    /// What a change `delta` of the emotion levels (one per direction) adds to every channel
    /// of a frame, mm: the emotion columns of the matrix times `delta`. Two renders of a take
    /// at the same timing differ by exactly this (plus f32 rounding). `None` when `delta` does
    /// not have one level per direction.
    pub fn emotion_displacement(&self, delta: &[f64]) -> Option<Vec<f64>> {
        let cols = self.emotion_columns();
        (cols.len() == delta.len()).then(|| {
            self.matrix
                .iter()
                .map(|row| cols.iter().zip(delta).map(|(&c, d)| row[c] * d).sum())
                .collect()
        })
    }
}

/// Truth of one take.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TakeTruth {
    /// Take name, e.g. `s03_happy` (the file stem).
    pub name: String,
    /// Sentence id, e.g. `s03`.
    pub sentence: String,
    /// 0-based sentence index.
    pub sentence_index: usize,
    /// Emotion name; every frame of the take carries it.
    pub emotion: String,
    /// Level actually rendered on the first emotion direction: base level x this sentence's
    /// intensity (the emotion source is this plus a slow drift).
    pub emotion_level: f64,
    /// Level actually rendered on every emotion direction: base point x this sentence's
    /// intensity (empty in truth written before emotion spaces existed: read it with
    /// [`TakeTruth::levels`]).
    #[serde(default)]
    pub emotion_levels: Vec<f64>,
    /// Seed of the take's drift, blinks, head motion and noise.
    pub seed: u64,
    /// Frame rate.
    pub rate_hz: f64,
    /// Canonical time (seconds into the sentence) of each frame.
    pub warp: Vec<f64>,
    /// Source values, one row per frame, one column per source.
    pub sources: Vec<Vec<f64>>,
    /// Blinks, real time.
    pub blinks: Vec<BlinkEvent>,
    /// Brow emphasis events, canonical time.
    pub brow_events: Vec<BrowEvent>,
    /// The sentence's viseme segments, canonical time.
    pub segments: Vec<Segment>,
}

impl TakeTruth {
    /// Number of frames.
    pub fn n_frames(&self) -> usize {
        self.sources.len()
    }

    /// Level rendered on every emotion direction; `[emotion_level]` for truth written with a
    /// single emotion source.
    pub fn levels(&self) -> Vec<f64> {
        if self.emotion_levels.is_empty() {
            vec![self.emotion_level]
        } else {
            self.emotion_levels.clone()
        }
    }

    /// One source's time series.
    pub fn source(&self, source: usize) -> Vec<f64> {
        self.sources.iter().map(|row| row[source]).collect()
    }
}

/// Truth of a whole session.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SessionTruth {
    /// Session-wide model.
    pub mixing: MixingTruth,
    /// Per-take truth, in manifest order.
    pub takes: Vec<TakeTruth>,
}

impl SessionTruth {
    /// (emotion, sentence id) of every frame of the session, takes concatenated in order.
    pub fn frame_labels(&self) -> Vec<(&str, &str)> {
        self.takes
            .iter()
            .flat_map(|t| {
                std::iter::repeat_n((t.emotion.as_str(), t.sentence.as_str()), t.n_frames())
            })
            .collect()
    }

    /// The take called `name`.
    pub fn take(&self, name: &str) -> Option<&TakeTruth> {
        self.takes.iter().find(|t| t.name == name)
    }
}

fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), SynthError> {
    let text = serde_json::to_string(value).map_err(|source| SynthError::Json {
        path: path.into(),
        source,
    })?;
    fs::write(path, text).map_err(|source| SynthError::Io {
        path: path.into(),
        source,
    })
}

fn read_json<T: for<'de> Deserialize<'de>>(path: &Path) -> Result<T, SynthError> {
    let text = fs::read_to_string(path).map_err(|source| SynthError::Io {
        path: path.into(),
        source,
    })?;
    serde_json::from_str(&text).map_err(|source| SynthError::Json {
        path: path.into(),
        source,
    })
}

/// Writes `truth/mixing.json` and one `truth/<take>.json` per take under `dir`.
///
/// # Errors
/// [`SynthError::Io`] or [`SynthError::Json`] naming the file.
pub fn write_truth(dir: &Path, truth: &SessionTruth) -> Result<(), SynthError> {
    let tdir = dir.join(TRUTH_DIR);
    fs::create_dir_all(&tdir).map_err(|source| SynthError::Io {
        path: tdir.clone(),
        source,
    })?;
    write_json(&tdir.join(MIXING_FILE), &truth.mixing)?;
    for take in &truth.takes {
        write_json(&tdir.join(format!("{}.json", take.name)), take)?;
    }
    Ok(())
}

/// Reads the truth of the session in `dir`: `truth/mixing.json` plus the truth of every take
/// listed in `dir/session.toml`, in manifest order.
///
/// # Errors
/// The manifest cannot be loaded, or a truth file is missing or malformed.
pub fn load_truth(dir: &Path) -> Result<SessionTruth, SynthError> {
    let session = crate::session::Session::load(&dir.join(crate::session::SESSION_FILE))?;
    let tdir = dir.join(TRUTH_DIR);
    let mixing = read_json(&tdir.join(MIXING_FILE))?;
    let takes = session
        .takes
        .iter()
        .map(|t| {
            let stem = Path::new(&t.file)
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or(&t.file);
            read_json(&tdir.join(format!("{stem}.json")))
        })
        .collect::<Result<_, _>>()?;
    Ok(SessionTruth { mixing, takes })
}
