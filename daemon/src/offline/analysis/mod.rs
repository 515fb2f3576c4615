//! `emoshift analyze`: give the components their meaning (section 4 of the method).
//!
//! Every take of the manifest is projected onto the model. Pairs of takes with the same
//! sentence and different emotions give `d_emotion` (DTW-aligned RMS difference per component,
//! the method's metric, reported and charted) and `d_level` (RMS difference of take means).
//! The emotion components are those whose take levels differ between emotions, by a blocked F
//! test across the paired takes ([`space`]): emotion is a space, not one axis, and each named
//! emotion gets a point in it (the mean over its takes, with the spread). Region metrics
//! `d_region,i` on the mouth, eyebrows and eyelids label the speech, eyebrow and eyelid
//! components (thresholds in [`ica_core::interpret::LabelRules`]).
//!
//! [`analyze_session`] reads the session sentence by sentence and keeps only per-take and
//! per-pair summaries between sentences ([`SessionStats`]), so memory does not grow with the
//! session (issue 18); [`analyze`] is the same accumulator over takes already in memory.

pub mod advice;
mod html;
mod map;
pub mod space;
mod stats;
mod streamed;
mod svg;

pub use stats::{SessionStats, TakeSeries};
pub use streamed::analyze_session;
pub use svg::{timeline_takes, TimelineTake};

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, Context, Result};
use ica_core::interpret::LabelRules;
use ica_core::model::{IcaModel, Role};
use replay::session::{Regions, Session, SessionError};
use serde::Serialize;

use crate::offline::{self, Projected};

/// Region names whose metrics decide roles, with the role they give.
pub const ROLE_REGIONS: [(&str, Role); 3] = [
    ("mouth", Role::Speech),
    ("eyebrows", Role::Eyebrows),
    ("eyelids", Role::Eyelids),
];

/// Sentences each emotion should be recorded in: the default script of `emoshift session`
/// records this many, and `analyze` advises at least this many. Chosen from the measured curve
/// of `docs/session.md` (`scripts/sentence-curve`): from 6 sentences every generator session
/// finds all its roles; 8 lowers the transfer error further (median 0.044, worst 0.062).
pub const MIN_SENTENCES_PER_EMOTION: usize = 8;

/// DTW band as a share of the longer take of a pair: the generator's warps stay within ±20 %.
pub const DTW_BAND_SHARE: f64 = 0.25;

/// One analysed take.
#[derive(Debug, Clone, Serialize)]
pub struct TakeSummary {
    /// File, as the manifest names it.
    pub file: String,
    /// Sentence id.
    pub sentence: String,
    /// Emotion name.
    pub emotion: String,
    /// Frames.
    pub frames: usize,
    /// Mean of each component over the take.
    pub component_means: Vec<f64>,
}

/// One pair used for `d_emotion`.
#[derive(Debug, Clone, Serialize)]
pub struct PairSummary {
    /// Sentence id.
    pub sentence: String,
    /// First take's file and emotion.
    pub a: (String, String),
    /// Second take's file and emotion.
    pub b: (String, String),
    /// Aligned samples.
    pub aligned_samples: usize,
}

/// Metrics and role of one component.
#[derive(Debug, Clone, Serialize)]
pub struct ComponentReport {
    /// Component index.
    pub index: usize,
    /// `emotion`, `speech`, `eyebrows`, `eyelids` or `other`.
    pub role: Role,
    /// `d_emotion` (absent without pairs).
    pub d_emotion: Option<f64>,
    /// `d_level`: RMS over pairs of the difference of take means (absent without pairs); its
    /// clear peak labels emotion.
    pub d_level: Option<f64>,
    /// `d_region` for every region of the regions file.
    pub d_region: BTreeMap<String, f64>,
    /// Marker-space displacement of one unit of the component (mm, mixing column norm).
    pub mixing_norm_mm: f64,
    /// The emotion effect on the component's take levels (absent without pairs).
    pub emotion_effect: Option<ica_core::interpret::EmotionEffect>,
}

/// The whole analysis, written as `report.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// Model file analysed.
    pub model: String,
    /// Manifest used.
    pub manifest: String,
    /// Components with metrics and roles.
    pub components: Vec<ComponentReport>,
    /// The emotion component(s).
    pub emotion_components: Vec<usize>,
    /// Whether `d_emotion` could be measured, and if not why.
    pub emotion_measured: bool,
    /// Why emotion was not measured or no clear peak was found (empty when it was).
    pub emotion_note: String,
    /// Level of the main emotion component per emotion name.
    pub levels: BTreeMap<String, f64>,
    /// The emotion space: components, each emotion's point, emotions that cannot be told apart.
    pub space: Option<space::EmotionSpace>,
    /// Pairs used for `d_emotion`.
    pub pairs: Vec<PairSummary>,
    /// Takes analysed.
    pub takes: Vec<TakeSummary>,
    /// Thresholds of the labelling rule.
    pub thresholds: LabelRules,
    /// DTW band as a share of the longer take of each pair.
    pub dtw_band_share: f64,
    /// Marker indices of each region.
    pub regions: BTreeMap<String, Vec<String>>,
    /// The model's own quality report (head decision, stability, residuals, warnings).
    pub quality: ica_core::quality::ModelQuality,
    /// Components that nearly passed the emotion test.
    pub near_misses: Vec<advice::NearMiss>,
    /// The fewest sentences any emotion was recorded with.
    pub sentences_per_emotion: usize,
    /// What the session lacks, one line each, as `analyze` prints them (see [`advice::lines`]).
    pub advice: Vec<String>,
}

/// Inputs of an analysis.
#[derive(Debug)]
pub struct Inputs<'a> {
    /// The model.
    pub model: &'a IcaModel,
    /// Its file (for the report).
    pub model_path: &'a Path,
    /// The manifest file.
    pub manifest_path: &'a Path,
    /// The regions file.
    pub regions_path: &'a Path,
}

/// A projected take of the session.
#[derive(Debug)]
pub struct SessionTake {
    /// Manifest entry.
    pub file: String,
    /// Sentence id.
    pub sentence: String,
    /// Emotion name.
    pub emotion: String,
    /// Components over the take.
    pub projected: Projected,
}

/// Loads and projects every take of a manifest, each cut to its range.
///
/// # Errors
/// Unreadable takes, or a take sharing no marker with the model.
pub fn project_session(model: &IcaModel, session: &Session) -> Result<Vec<SessionTake>> {
    session
        .takes
        .iter()
        .zip(offline::session_inputs(session))
        .map(|(entry, input)| {
            let take = input.load(replay::C3dDecoding::CrossChecked)?;
            let map = offline::match_take(model, &take, &input.path)?;
            let projected = offline::project_take(model, &offline::to_model_order(&take, &map))?;
            Ok(SessionTake {
                file: entry.file.clone(),
                sentence: entry.sentence.clone(),
                emotion: entry.emotion.clone(),
                projected,
            })
        })
        .collect()
}

/// Resolves the regions file against the model's labels; the role regions must be present.
///
/// # Errors
/// Unreadable file, a region naming no marker, or a missing mouth/eyebrows/eyelids region.
pub fn resolve_regions(path: &Path, model: &IcaModel) -> Result<BTreeMap<String, Vec<usize>>> {
    let regions = Regions::load(path)?;
    let resolved = regions.resolve(model.labels()).map_err(|e| match e {
        // The model's markers are the take's less those train left out: say so, not "take".
        SessionError::UnknownLabel {
            region,
            label,
            hint,
        } => anyhow!(
            "{}: region {region:?} names marker {label:?}, which the model does not have{hint}. \
             train leaves out markers missing in most frames and says which: remove or correct \
             the name in the file and run again",
            path.display()
        ),
        e => anyhow::Error::new(e).context(path.display().to_string()),
    })?;
    for (name, _) in ROLE_REGIONS {
        if !resolved.contains_key(name) {
            bail!(
                "{}: no {name:?} region; analyze needs mouth, eyebrows and eyelids",
                path.display()
            );
        }
    }
    Ok(resolved)
}

/// Runs the analysis on projected takes held together (the whole session in memory): the
/// reference the streamed [`analyze_session`] must match, and the path for callers that
/// already hold the takes.
///
/// # Errors
/// A metric that cannot be computed (bad shapes, non-finite components).
pub fn analyze(
    inputs: &Inputs<'_>,
    takes: &[SessionTake],
    regions: &BTreeMap<String, Vec<usize>>,
) -> Result<Report> {
    let m = inputs.model.components();
    let series: Vec<Vec<f64>> = takes.iter().map(|t| t.projected.as_f64()).collect();
    let longest = series.iter().map(|s| s.len() / m).max().unwrap_or(0);
    let group: Vec<TakeSeries<'_>> = takes
        .iter()
        .zip(&series)
        .enumerate()
        .map(|(index, (t, s))| TakeSeries {
            index,
            file: &t.file,
            sentence: &t.sentence,
            emotion: &t.emotion,
            series: s,
        })
        .collect();
    let mut stats = SessionStats::new(m, longest);
    stats.add_group(&group)?;
    stats.finish(inputs, regions)
}

/// The takes the timeline chart draws ([`timeline_takes`]), from takes held in memory.
pub fn timeline_of(report: &Report, takes: &[SessionTake]) -> Vec<TimelineTake> {
    timeline_takes(report)
        .into_iter()
        .filter_map(|i| takes.get(i))
        .map(|t| TimelineTake {
            sentence: t.sentence.clone(),
            emotion: t.emotion.clone(),
            u: t.projected.u.clone(),
        })
        .collect()
}

/// The axes of the emotion space a model gets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Axes {
    /// Fitted over every component ([`ica_core::interpret::emotion_basis`]): the space does
    /// not depend on how ICA split the emotion (issue 34).
    #[default]
    Fitted,
    /// The emotion components themselves, one per axis (the space before issue 34).
    Components,
}

impl std::str::FromStr for Axes {
    type Err = String;

    fn from_str(s: &str) -> Result<Axes, String> {
        match s {
            "fitted" => Ok(Axes::Fitted),
            "components" => Ok(Axes::Components),
            _ => Err(format!(
                "unknown axes {s:?} (expected fitted or components)"
            )),
        }
    }
}

/// Stores roles and the emotion space (its `axes`, points, main component) in the model.
/// Fitted axes fall back to the components when the session shows no fitted axis.
///
/// # Errors
/// A component index outside the model (an internal invariant).
pub fn write_into_model(model: &mut IcaModel, report: &Report, axes: Axes) -> Result<()> {
    let fitted = report.space.as_ref().and_then(|space| {
        let basis = space.basis.as_ref().filter(|b| !b.axes.is_empty())?;
        let conditioning = space.conditioning.clone()?;
        (axes == Axes::Fitted).then_some((space, basis, conditioning))
    });
    if let Some((space, basis, conditioning)) = fitted {
        model.set_fitted_space(
            space.components.clone(),
            space.main,
            report.levels.clone(),
            ica_core::model::FittedSpace {
                axes: basis.axes.clone(),
                moves: basis.moves.clone(),
                points: basis.points.clone(),
                persistence: basis.persistence.clone(),
                conditioning,
            },
        )?;
        for c in &report.components {
            model.set_role(c.index, c.role)?;
        }
        return Ok(());
    }
    match &report.space {
        Some(space) if !space.components.is_empty() => {
            let main = space.main.expect("a non-empty space has a main component");
            model.set_emotion_space(
                space.components.clone(),
                main,
                space.points.clone(),
                space.persistence.clone(),
            )?;
        }
        _ => model.clear_emotion_space(),
    }
    // After the space: its components that are not emotion axes keep their region role.
    for c in &report.components {
        model.set_role(c.index, c.role)?;
    }
    Ok(())
}

/// Writes `report.json`, `components.svg`, `timeline.svg` (of `timeline`, the takes
/// [`timeline_takes`] picks) and `report.html` into `dir`.
///
/// # Errors
/// Any file that cannot be written.
pub fn write_report(
    dir: &Path,
    report: &Report,
    timeline: &[TimelineTake],
) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let write = |name: &str, text: String| -> Result<PathBuf> {
        let path = dir.join(name);
        std::fs::write(&path, text).with_context(|| format!("cannot write {}", path.display()))?;
        Ok(path)
    };
    let json = serde_json::to_string_pretty(report).context("report serialisation")?;
    let components = svg::components_chart(report);
    let timeline = svg::timeline_chart(report, timeline);
    let mut written = Vec::new();
    if let Some(map) = map::emotion_map(report) {
        written.push(write("emotion_map.svg", map)?);
    }
    written.extend([
        write("report.json", json)?,
        write("components.svg", components)?,
        write("timeline.svg", timeline)?,
        write("report.html", html::page(report))?,
    ]);
    Ok(written)
}
