//! The arguments of the offline commands: takes and models on disk.

use std::path::PathBuf;

use clap::Args;

/// `emoshift info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// The take (.c3d, .trc or .csv).
    pub file: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// `emoshift convert`.
#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// Input take (.c3d, .trc or .csv).
    pub input: PathBuf,
    /// Output take; its extension picks the format.
    pub output: PathBuf,
    /// The frames kept.
    #[command(flatten)]
    pub range: super::RangeArgs,
    /// Overwrite the output if it exists.
    #[arg(long)]
    pub force: bool,
}

/// `emoshift train`.
#[derive(Debug, Args)]
pub struct TrainArgs {
    /// Session manifest listing the takes (session.toml: `rate_hz`, required, then
    /// `[[take]]` tables with file, sentence, emotion, and optional start/end: the frames used,
    /// as `convert --start/--end` writes them).
    #[arg(long)]
    pub manifest: Option<PathBuf>,
    /// Take files (in addition to the manifest's).
    pub files: Vec<PathBuf>,
    /// Where to write the model (JSON).
    #[arg(long)]
    pub out: PathBuf,
    /// Share of the variance the principal components keep, 0.90 to 0.999 (default 0.97).
    #[arg(long)]
    pub variance: Option<f64>,
    /// Keep exactly this many components instead of a variance share.
    #[arg(long)]
    pub components: Option<usize>,
    /// Seed of the FastICA initialisations.
    #[arg(long, default_value_t = ica_core::fit::DEFAULT_SEED)]
    pub seed: u64,
    /// FastICA restarts; the one with the largest negentropy is kept.
    #[arg(long, default_value_t = ica_core::fit::DEFAULT_RESTARTS)]
    pub restarts: usize,
    /// Iteration cap per restart.
    #[arg(long, default_value_t = ica_core::fit::DEFAULT_MAX_ITER)]
    pub max_iter: usize,
    /// Convergence tolerance.
    #[arg(
        long,
        default_value_t = ica_core::fit::DEFAULT_TOL,
        value_parser = super::values::positive,
        allow_negative_numbers = true
    )]
    pub tol: f64,
    /// Model rate in Hz; takes at other rates are resampled (default: the manifest's
    /// `rate_hz`, else the first take's rate).
    #[arg(long, value_parser = super::values::positive)]
    pub rate: Option<f64>,
    /// Leave out markers missing in more than this share of the frames.
    #[arg(
        long,
        default_value_t = crate::offline::training::DEFAULT_MAX_MISSING,
        value_parser = super::values::share
    )]
    pub max_missing: f64,
    /// Glitch speed limit: auto, off, or mm/s. Faster moves are treated as missing.
    #[arg(long, default_value = "auto")]
    pub max_speed: String,
    /// Rigid head markers: auto, none, or comma-separated labels or globs (default: the
    /// regions file's head_reference, else auto: common head-marker names, then the markers
    /// the capture shows to be rigid).
    #[arg(long)]
    pub head_reference: Option<String>,
    /// Case-insensitive name patterns of head markers tried by auto before the geometry.
    #[arg(
        long,
        value_delimiter = ',',
        default_values_t = crate::offline::training::DEFAULT_HEAD_PATTERNS.map(String::from)
    )]
    pub head_patterns: Vec<String>,
    /// Regions file (default: regions.toml beside the manifest, if any).
    #[arg(long)]
    pub regions: Option<PathBuf>,
    /// Do not learn per-marker plausible regions (which drop swapped or drifting labels).
    #[arg(long)]
    pub no_bounds: bool,
    /// Threads for the passes over the takes (0: one per core; 1 stays on one core). The model
    /// is the same whatever the count.
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Stream the takes even when the session is short enough to train in memory (sessions
    /// longer than 4,000 frames always stream, in bounded memory).
    #[arg(long)]
    pub stream: bool,
    /// Overwrite the output if it exists.
    #[arg(long)]
    pub force: bool,
}

/// `emoshift project`.
#[derive(Debug, Args)]
pub struct ProjectArgs {
    /// The model (JSON).
    #[arg(long)]
    pub model: PathBuf,
    /// The take to project.
    pub file: PathBuf,
    /// Output CSV: `frame,time,c0,...,c{m-1}`. Written as the take is read, in blocks of
    /// frames, so memory does not grow with the take.
    #[arg(long)]
    pub out: PathBuf,
    /// Overwrite the output if it exists.
    #[arg(long)]
    pub force: bool,
    /// Frames read and projected at a time (tests and measurements).
    #[arg(long, hide = true, default_value_t = crate::offline::streamed::BLOCK_FRAMES)]
    pub block_frames: usize,
}

/// `emoshift edit`.
#[derive(Debug, Args)]
pub struct EditArgs {
    /// The model (JSON).
    #[arg(long)]
    pub model: PathBuf,
    /// The take to edit.
    pub file: PathBuf,
    /// Output take; its extension picks the format. Raw and emotion edits stream the take
    /// from file to output in blocks of frames (memory does not grow with the take; a mean-based
    /// --to-emotion reads the file twice); Copy & Replace and Copy & Add hold both takes whole.
    #[arg(long)]
    pub out: PathBuf,
    /// Translate component k by alpha (component units, |alpha| at most 100, as live):
    /// `--translate 2=0.5`, `--translate 2=-1` (repeatable).
    #[arg(long, value_parser = parse_translate, allow_hyphen_values = true)]
    pub translate: Vec<KeyValue>,
    /// Multiply component k by g (|g| at most 10, as live): `--gain 0=1.2` (repeatable).
    #[arg(long, value_parser = parse_gain, allow_hyphen_values = true)]
    pub gain: Vec<KeyValue>,
    /// Move the emotion towards a named level (needs an analysed model).
    #[arg(long, value_name = "NAME")]
    pub to_emotion: Option<String>,
    /// How far to move towards --to-emotion: 0 keeps the take, 1 reaches the level.
    #[arg(
        long,
        default_value_t = 1.0,
        requires = "to_emotion",
        value_parser = super::values::finite,
        allow_negative_numbers = true
    )]
    pub amount: f64,
    /// With --to-emotion: edit as the live daemon does, from a causal low-pass of the emotion
    /// component over this many seconds, instead of the take's mean (same output as `serve`).
    #[arg(
        long,
        value_name = "SECONDS",
        requires = "to_emotion",
        value_parser = super::values::non_negative,
        allow_negative_numbers = true
    )]
    pub lowpass: Option<f64>,
    /// Copy & Replace: take the emotion series of another take (DTW-aligned to this one; both
    /// takes are held whole in memory).
    #[arg(long, value_name = "OTHER")]
    pub replace_emotion_from: Option<PathBuf>,
    /// Copy & Add: add the emotion series of another take under --other-model (both takes are
    /// held whole in memory).
    #[arg(long, value_name = "OTHER", requires = "other_model")]
    pub add_emotion_from: Option<PathBuf>,
    /// The second model of Copy & Add.
    #[arg(long, value_name = "M2")]
    pub other_model: Option<PathBuf>,
    /// Keep the take's gaps in the output instead of filling them from the model.
    #[arg(long)]
    pub keep_gaps: bool,
    /// The frames written (the frames before are edited, not written, so the range is the
    /// whole edit's; the output numbers its frames as the input does).
    #[command(flatten)]
    pub range: super::RangeArgs,
    /// Overwrite the output if it exists.
    #[arg(long)]
    pub force: bool,
    /// Frames read and edited at a time (tests and measurements).
    #[arg(long, hide = true, default_value_t = crate::offline::streamed::BLOCK_FRAMES)]
    pub block_frames: usize,
    /// MiB of `--to-emotion`'s first pass kept for the edit, which then does not prepare and
    /// project those frames again (tests and measurements; 0 keeps none).
    #[arg(long, hide = true, default_value_t = crate::offline::streamed::KEEP_BYTES >> 20)]
    pub keep_mb: usize,
}

/// `emoshift inspect`.
#[derive(Debug, Args)]
pub struct InspectArgs {
    /// The model (JSON).
    pub model: PathBuf,
    /// Print the whole model as JSON.
    #[arg(long)]
    pub json: bool,
}

/// A `k=value` pair of `--translate` and `--gain`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KeyValue {
    /// Component index.
    pub key: usize,
    /// Value.
    pub value: f64,
}

fn parse_translate(text: &str) -> Result<KeyValue, String> {
    bounded(text, "alpha", protocol::MAX_ALPHA, " component units")
}

fn parse_gain(text: &str) -> Result<KeyValue, String> {
    bounded(text, "gain", protocol::MAX_GAIN, "")
}

/// The live controls' bounds hold offline too: past them an edit leaves any face.
fn bounded(text: &str, what: &str, max: f32, unit: &str) -> Result<KeyValue, String> {
    let kv = parse_key_value(text)?;
    if kv.value.abs() > f64::from(max) {
        let given = text.split_once('=').map_or(text, |(_, v)| v.trim());
        return Err(format!("{what} {given} is outside -{max}..{max}{unit}"));
    }
    Ok(kv)
}

fn parse_key_value(text: &str) -> Result<KeyValue, String> {
    let (k, v) = text
        .split_once('=')
        .ok_or_else(|| format!("expected k=value, got {text:?}"))?;
    let key = k
        .trim()
        .parse()
        .map_err(|_| format!("component index {k:?} is not a whole number"))?;
    let value: f64 = v
        .trim()
        .parse()
        .map_err(|_| format!("value {v:?} is not a number"))?;
    if !value.is_finite() {
        return Err(format!("value {v:?} is not finite"));
    }
    Ok(KeyValue { key, value })
}

/// `emoshift analyze`.
#[derive(Debug, Args)]
pub struct AnalyzeArgs {
    /// The model (JSON).
    #[arg(long)]
    pub model: PathBuf,
    /// Session manifest (session.toml) with sentence and emotion per take.
    #[arg(long)]
    pub manifest: PathBuf,
    /// Regions file (default: regions.toml beside the manifest).
    #[arg(long)]
    pub regions: Option<PathBuf>,
    /// Output folder for report.json, components.svg, timeline.svg and report.html.
    #[arg(long)]
    pub out: PathBuf,
    /// Store the roles and emotion levels in the model file.
    #[arg(long)]
    pub write_model: bool,
    /// Axes of the emotion space the model gets: fitted (over every component, whatever way
    /// ICA split the emotion) or components (the emotion components themselves, as before
    /// issue 34; for comparison).
    #[arg(long, default_value = "fitted")]
    pub axes: crate::offline::analysis::Axes,
    /// Overwrite the output if it exists.
    #[arg(long)]
    pub force: bool,
}
