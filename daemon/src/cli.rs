//! The command line: one clap-derive enum of subcommands, each a thin front end.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

/// emoshift: edit the emotion of facial motion capture, offline and live.
#[derive(Debug, Parser)]
#[command(name = "emoshift", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Write a synthetic paired session (takes, ground truth, session.toml, regions.toml).
    #[command(after_help = "Examples:\n  emoshift synth --out session\n  \
        emoshift synth --out s2 --seed 7 --sentences 4 --emotions neutral,sad,angry --format trc\n  \
        emoshift synth --out s3 --emotion-dims 2 --emotions neutral,happy,sad,angry\n  \
        emoshift synth --out s4 --emotions neutral,happy,calm --point calm=0.3,-0.4 --point happy=1,0.2\n\n\
        Emotion space: each emotion is a point, one level per emotion direction (1: smile + / \
        frown -, 2: brow knit + lip press, 3: inner brow raise + mouth corners down). Default \
        points: k=1 neutral 0, happy 1, frustrated -1; k=2 neutral (0,0), happy (1,0), frustrated \
        (-1,0.3), angry (-0.2,1), sad (-0.6,-0.8); k=3 the same with a third coordinate 0, except \
        sad (-0.3,-0.2,1), plus surprised (0.2,-1,0) and fear (-0.3,0.6,0.9). Other names get \
        spare points at least 0.5 from every other point. The truth (truth/mixing.json) records \
        every point.")]
    Synth(SynthArgs),
    /// Show a take's labels, rate, frame range, units and missing samples per marker.
    #[command(after_help = "Examples:\n  emoshift info take.c3d\n  emoshift info take.trc --json")]
    Info(InfoArgs),
    /// Convert a take between C3D, TRC and CSV (format chosen by extension; gaps kept).
    #[command(after_help = "Examples:\n  emoshift convert Facial-Sing.c3d x.trc\n  \
        emoshift convert x.trc y.c3d")]
    Convert(ConvertArgs),
    /// Learn an ICA model from takes.
    #[command(
        after_help = "Examples:\n  emoshift train --manifest session/session.toml --out model.json\n  \
        emoshift train take1.c3d take2.c3d --out model.json --components 10 --restarts 8"
    )]
    Train(TrainArgs),
    /// Project a take onto a model's components (CSV: frame,time,c0,...).
    #[command(
        after_help = "Example:\n  emoshift project --model model.json take.c3d --out components.csv"
    )]
    Project(ProjectArgs),
    /// Edit a take in component space and write it in any format.
    #[command(
        after_help = "Examples:\n  emoshift edit --model model.json take.c3d --out edited.c3d --translate 2=1.5\n  \
        emoshift edit --model model.json take.trc --out louder.trc --gain 0=1.3"
    )]
    Edit(EditArgs),
    /// Show what a model holds.
    #[command(
        after_help = "Examples:\n  emoshift inspect model.json\n  emoshift inspect model.json --json"
    )]
    Inspect(InspectArgs),
    /// Run the live service: receive frames, edit their emotion, send them to subscribers.
    #[command(
        after_help = "Examples:\n  emoshift serve --model model.json --send 127.0.0.1:9100\n  \
        emoshift serve --config emoshift.toml --listen 127.0.0.1:9000 --send 239.0.0.1:9100:flat-split"
    )]
    Serve(ServeArgs),
    /// Measure the service on loopback against a plain UDP relay: added latency, loss, throughput.
    #[command(after_help = "Example:\n  emoshift bench --performers 2 --clients 4 --seconds 3")]
    Bench(BenchArgs),
    /// Label the components (emotion, speech, eyebrows, eyelids) and write the report.
    #[command(
        after_help = "Example:\n  emoshift analyze --model model.json --manifest session/session.toml --out report --write-model"
    )]
    Analyze(AnalyzeArgs),
    /// Send a take over UDP at its rate, as a live source would (OSC /mocap/frame + labels).
    #[command(
        after_help = "Examples:\n  emoshift replay take.c3d --to 127.0.0.1:9000\n  \
        emoshift replay take.trc --to 127.0.0.1:9000 --speed 2 --loop --start-frame 120"
    )]
    Replay(ReplayArgs),
    /// Run the whole chain on an embedded default: synth, train, analyze, serve, replay with an
    /// emotion sweep, receive, summarise.
    #[command(
        after_help = "Examples:\n  emoshift demo\n  emoshift demo --keep demo-out\n  emoshift demo --real"
    )]
    Demo(DemoArgs),
}

/// `emoshift synth`.
#[derive(Debug, Args)]
pub struct SynthArgs {
    /// Output folder (created if needed).
    #[arg(long)]
    pub out: PathBuf,
    /// Seed of every random choice; the same seed writes the same session.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Number of sentences; every sentence is rendered in every emotion.
    #[arg(long, default_value_t = 8)]
    pub sentences: usize,
    /// Emotion names, comma separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "neutral,happy,frustrated"
    )]
    pub emotions: Vec<String>,
    /// Number of emotion directions, 1 to 3 (default: the coordinate count of --point, else 1).
    #[arg(long, value_name = "K")]
    pub emotion_dims: Option<usize>,
    /// An explicit point for an emotion of --emotions: one level per emotion direction.
    /// Repeat the flag, or separate points with ';'.
    #[arg(long = "point", value_name = "NAME=X[,Y[,Z]]", value_delimiter = ';')]
    pub points: Vec<replay::synth::EmotionPoint>,
    /// Frame rate in Hz.
    #[arg(long, default_value_t = 120.0)]
    pub rate: f64,
    /// Add small rigid head motion.
    #[arg(long)]
    pub head_motion: bool,
    /// Face markers: full (109-marker face) or sparse (41 face markers).
    #[arg(long, default_value = "full")]
    pub markers: replay::synth::MarkerSet,
    /// Marker names: descriptive (MouthCornerL), snake (mouth_01) or numbered (M001).
    #[arg(long, default_value = "descriptive")]
    pub names: replay::synth::Naming,
    /// Rigid head markers: band (4 head-band markers), vicon (LFHD RFHD LBHD RBHD) or none (and
    /// a nose that moves with the face).
    #[arg(long, default_value = "band")]
    pub rigid: replay::synth::RigidMarkers,
    /// Move each face marker at random by up to this many mm (and the face's width and height
    /// by up to 8 %), so the face is not the default one.
    #[arg(long, default_value_t = 0.0)]
    pub placement_jitter: f64,
    /// File format of the takes: c3d, trc or csv.
    #[arg(long, default_value = "c3d")]
    pub format: String,
}

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
}

/// `emoshift train`.
#[derive(Debug, Args)]
pub struct TrainArgs {
    /// Session manifest listing the takes (session.toml).
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
    #[arg(long, default_value_t = ica_core::fit::DEFAULT_TOL)]
    pub tol: f64,
    /// Model rate in Hz; takes at other rates are resampled (default: the first take's rate).
    #[arg(long)]
    pub rate: Option<f64>,
    /// Leave out markers missing in more than this share of the frames.
    #[arg(long, default_value_t = 0.5)]
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
        default_value = "LFHD,RFHD,LBHD,RBHD,head*,hat*,helmet*"
    )]
    pub head_patterns: Vec<String>,
    /// Regions file (default: regions.toml beside the manifest, if any).
    #[arg(long)]
    pub regions: Option<PathBuf>,
    /// Do not learn per-marker plausible regions (which drop swapped or drifting labels).
    #[arg(long)]
    pub no_bounds: bool,
}

/// `emoshift project`.
#[derive(Debug, Args)]
pub struct ProjectArgs {
    /// The model (JSON).
    #[arg(long)]
    pub model: PathBuf,
    /// The take to project.
    pub file: PathBuf,
    /// Output CSV: `frame,time,c0,...,c{m-1}`.
    #[arg(long)]
    pub out: PathBuf,
}

/// `emoshift edit`.
#[derive(Debug, Args)]
pub struct EditArgs {
    /// The model (JSON).
    #[arg(long)]
    pub model: PathBuf,
    /// The take to edit.
    pub file: PathBuf,
    /// Output take; its extension picks the format.
    #[arg(long)]
    pub out: PathBuf,
    /// Translate component k by alpha: `--translate 2=0.5` (repeatable).
    #[arg(long, value_parser = parse_key_value)]
    pub translate: Vec<KeyValue>,
    /// Multiply component k by g: `--gain 0=1.2` (repeatable).
    #[arg(long, value_parser = parse_key_value)]
    pub gain: Vec<KeyValue>,
    /// Move the emotion towards a named level (needs an analysed model).
    #[arg(long, value_name = "NAME")]
    pub to_emotion: Option<String>,
    /// How far to move towards --to-emotion: 0 keeps the take, 1 reaches the level.
    #[arg(long, default_value_t = 1.0)]
    pub amount: f64,
    /// With --to-emotion: edit as the live daemon does, from a causal low-pass of the emotion
    /// component over this many seconds, instead of the take's mean (same output as `serve`).
    #[arg(long, value_name = "SECONDS", requires = "to_emotion")]
    pub lowpass: Option<f64>,
    /// Copy & Replace: take the emotion series of another take (DTW-aligned to this one).
    #[arg(long, value_name = "OTHER")]
    pub replace_emotion_from: Option<PathBuf>,
    /// Copy & Add: add the emotion series of another take under --other-model.
    #[arg(long, value_name = "OTHER", requires = "other_model")]
    pub add_emotion_from: Option<PathBuf>,
    /// The second model of Copy & Add.
    #[arg(long, value_name = "M2")]
    pub other_model: Option<PathBuf>,
    /// Keep the take's gaps in the output instead of filling them from the model.
    #[arg(long)]
    pub keep_gaps: bool,
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

/// `emoshift serve`. Flags override the config file.
#[derive(Debug, Args)]
pub struct ServeArgs {
    /// TOML config file (every flag has a key; see docs/emoshift.toml).
    #[arg(long, env = "EMOSHIFT_CONFIG")]
    pub config: Option<PathBuf>,
    /// Model file (JSON).
    #[arg(long, env = "EMOSHIFT_MODEL")]
    pub model: Option<PathBuf>,
    /// Frame socket, IP:PORT [default: 127.0.0.1:9000].
    #[arg(long, value_name = "IP:PORT")]
    pub listen: Option<String>,
    /// Control socket, IP:PORT [default: 127.0.0.1:9001].
    #[arg(long, value_name = "IP:PORT")]
    pub control: Option<String>,
    /// Static subscriber HOST:PORT[:profile] (compact, flat-split, components); repeatable,
    /// replaces the config's list.
    #[arg(long, value_name = "HOST:PORT[:PROFILE]")]
    pub send: Vec<String>,
    /// Low-pass window of the emotion edit, seconds [default: 1].
    #[arg(long)]
    pub lowpass: Option<f32>,
}

/// `emoshift bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Senders (performers), each at 120 Hz.
    #[arg(long, default_value_t = 1)]
    pub performers: usize,
    /// Receivers (subscribers).
    #[arg(long, default_value_t = 2)]
    pub clients: usize,
    /// Seconds of each timed run.
    #[arg(long, default_value_t = 3.0)]
    pub seconds: f64,
    /// The daemon's `poll_window_us` (0: the processing thread always parks).
    #[arg(long, default_value_t = crate::serve::config::DEFAULT_POLL_WINDOW_US)]
    pub poll_window_us: u64,
}

/// A `k=value` pair of `--translate` and `--gain`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KeyValue {
    /// Component index.
    pub key: usize,
    /// Value.
    pub value: f64,
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
}

/// `emoshift replay`.
#[derive(Debug, Args)]
pub struct ReplayArgs {
    /// The take (.c3d, .trc or .csv).
    pub file: PathBuf,
    /// Where to send, HOST:PORT (e.g. the daemon's --listen address).
    #[arg(long, value_name = "HOST:PORT")]
    pub to: String,
    /// Playback speed: 2 sends twice as fast (capture times stay in take time).
    #[arg(long, default_value_t = 1.0)]
    pub speed: f64,
    /// After the last frame start again from the first, until Ctrl-C; frame numbers keep
    /// increasing.
    #[arg(long = "loop")]
    pub looping: bool,
    /// Index (0-based, whatever the file numbers it) of the first frame to send.
    #[arg(long, default_value_t = 0, value_name = "N")]
    pub start_frame: usize,
    /// Layout id sent in /mocap/labels.
    #[arg(long, default_value_t = 0, value_name = "ID")]
    pub layout_id: i32,
    /// Frame encoding: blob (`,ihbb`, with a missing-marker mask) or flat (`,ih` + floats, NaN
    /// for missing).
    #[arg(long, value_enum, default_value_t = WireFormat::Blob)]
    pub format: WireFormat,
    /// Overdue frames sent back to back after a stall; further behind, skip to the present.
    #[arg(long, default_value_t = replay::pacer::DEFAULT_MAX_BEHIND_FRAMES, value_name = "FRAMES")]
    pub max_behind: u64,
}

/// The `/mocap/frame` encoding of `emoshift replay`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum WireFormat {
    /// `,ihbb`: frame, time, missing-marker mask blob, positions blob.
    Blob,
    /// `,ih` then 3 floats per marker, all NaN for a missing marker.
    Flat,
}

/// `emoshift demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Keep everything the demo made in this folder (default: a temporary folder of which only
    /// the report stays).
    #[arg(long, value_name = "DIR")]
    pub keep: Option<PathBuf>,
    /// Run on the bundled real capture (Facial-Sing) instead of a synthetic session; there are
    /// no emotion pairs, so there is no sweep.
    #[arg(long)]
    pub real: bool,
    /// Seed of the synthetic session.
    #[arg(long, default_value_t = 7)]
    pub seed: u64,
}
