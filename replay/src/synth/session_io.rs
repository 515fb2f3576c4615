//! A whole synthetic session, in memory or written to a folder:
//! `<take>.<ext>` per take, `session.toml`, `regions.toml` and `truth/*.json`.

use std::fs;
use std::path::{Path, PathBuf};

use super::mixing::HEAD_PIVOT;
use super::render::NOISE_STD_MM;
use super::truth::{write_truth, EmotionLevel, MixingTruth, SessionTruth};
use super::{FaceGeometry, RenderedTake, Synth, SynthError, SynthParams};
use crate::session::{Regions, Session, SessionTake, REGIONS_FILE, SESSION_FILE};
use crate::{Format, Take};

/// A generated session held in memory.
#[derive(Debug, Clone)]
pub struct SynthSession {
    /// The takes, in manifest order.
    pub takes: Vec<Take>,
    /// The manifest (file names use the extension of the format asked for).
    pub session: Session,
    /// The region map.
    pub regions: Regions,
    /// The ground truth.
    pub truth: SessionTruth,
}

/// What [`write_session`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct SessionSummary {
    /// The session folder.
    pub dir: PathBuf,
    /// The manifest path.
    pub manifest: PathBuf,
    /// Take names (file stems), in order.
    pub takes: Vec<String>,
    /// Frames of each take, in order.
    pub frames: Vec<usize>,
    /// Frames over all takes.
    pub total_frames: usize,
    /// Markers per take.
    pub markers: usize,
}

impl Synth {
    /// The session-wide truth: labels, sources, mixing matrix, rest shape, regions, points.
    pub fn mixing_truth(&self) -> MixingTruth {
        let face = self.face();
        let regions = face.region_labels();
        let cols = self.source_layout();
        MixingTruth {
            labels: face.labels(),
            sources: cols.source_infos(),
            matrix: self
                .mixing()
                .chunks(cols.count())
                .map(<[f64]>::to_vec)
                .collect(),
            rest: self.rest().to_vec(),
            regions,
            emotions: self
                .params()
                .emotions
                .iter()
                .map(|e| {
                    let point = self.point_of(e).expect("session emotions have points");
                    EmotionLevel {
                        name: e.clone(),
                        level: point[0],
                        point: point.to_vec(),
                    }
                })
                .collect(),
            emotion_columns: cols.emotions().collect(),
            rate_hz: self.params().rate_hz,
            seed: self.params().seed,
            noise_std_mm: NOISE_STD_MM,
            head_motion: self.params().head_motion,
            layout: self.params().layout.describe(),
            variation: self.params().variation.describe(),
            head_pivot: HEAD_PIVOT,
        }
    }
}

/// Generates a whole session in memory; take files are named `<take>.<format extension>`.
///
/// # Errors
/// Invalid parameters ([`SynthParams::validate`]).
pub fn generate_session(params: &SynthParams, format: Format) -> Result<SynthSession, SynthError> {
    let synth = Synth::new(params.clone())?;
    let rendered: Vec<RenderedTake> = synth.render_all()?;
    let session = Session {
        rate_hz: params.rate_hz,
        takes: rendered
            .iter()
            .map(|r| {
                SessionTake::whole(
                    format!("{}.{}", r.truth.name, format.extension()),
                    r.truth.sentence.clone(),
                    r.truth.emotion.clone(),
                )
            })
            .collect(),
        base_dir: PathBuf::new(),
    };
    // The default face keeps its glob patterns; other layouts list their labels, since their
    // names may say nothing about the region.
    let regions = Regions {
        regions: if params.layout.is_standard() {
            FaceGeometry::region_patterns()
        } else {
            synth.face().region_labels()
        },
    };
    let mixing = synth.mixing_truth();
    let (takes, truths) = rendered.into_iter().map(|r| (r.take, r.truth)).unzip();
    Ok(SynthSession {
        takes,
        session,
        regions,
        truth: SessionTruth {
            mixing,
            takes: truths,
        },
    })
}

fn write_text(path: &Path, text: &str) -> Result<(), SynthError> {
    fs::write(path, text).map_err(|source| SynthError::Io {
        path: path.into(),
        source,
    })
}

/// Generates a session and writes it to `dir` (created if needed): one take file per take in
/// `format`, `session.toml`, `regions.toml` and `truth/`.
///
/// # Errors
/// Invalid parameters, or any file that cannot be written (a take writer's error is passed on
/// as [`SynthError::Write`] naming the file).
pub fn write_session(
    dir: &Path,
    params: &SynthParams,
    format: Format,
) -> Result<SessionSummary, SynthError> {
    let generated = generate_session(params, format)?;
    fs::create_dir_all(dir).map_err(|source| SynthError::Io {
        path: dir.into(),
        source,
    })?;
    for (take, entry) in generated.takes.iter().zip(&generated.session.takes) {
        let path = dir.join(&entry.file);
        crate::save(&path, take).map_err(|source| SynthError::Write { path, source })?;
    }
    write_truth(dir, &generated.truth)?;
    let manifest = dir.join(SESSION_FILE);
    write_text(&manifest, &generated.session.to_toml()?)?;
    write_text(&dir.join(REGIONS_FILE), &generated.regions.to_toml()?)?;
    let frames: Vec<usize> = generated.takes.iter().map(Take::n_frames).collect();
    Ok(SessionSummary {
        dir: dir.into(),
        manifest,
        takes: generated
            .truth
            .takes
            .iter()
            .map(|t| t.name.clone())
            .collect(),
        total_frames: frames.iter().sum(),
        frames,
        markers: generated.takes.first().map_or(0, Take::n_markers),
    })
}
