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
        emoshift synth --out s2 --seed 7 --sentences 4 --emotions neutral,sad,angry --format trc")]
    Synth(SynthArgs),
    /// Show a take's labels, rate, frame range, units and missing samples per marker.
    #[command(after_help = "Examples:\n  emoshift info take.c3d\n  emoshift info take.trc --json")]
    Info(InfoArgs),
    /// Convert a take between C3D, TRC and CSV (format chosen by extension; gaps kept).
    #[command(after_help = "Examples:\n  emoshift convert Facial-Sing.c3d x.trc\n  \
        emoshift convert x.trc y.c3d")]
    Convert(ConvertArgs),
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
    /// Frame rate in Hz.
    #[arg(long, default_value_t = 120.0)]
    pub rate: f64,
    /// Add small rigid head motion.
    #[arg(long)]
    pub head_motion: bool,
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
