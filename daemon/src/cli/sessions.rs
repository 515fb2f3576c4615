//! The arguments of the commands that make sessions: a synthetic face, or an effect injected
//! into real captures.

use std::path::PathBuf;

use clap::Args;

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
    #[arg(long, default_value_t = 120.0, value_parser = super::values::positive)]
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
    #[arg(long, default_value_t = 0.0, value_parser = super::values::non_negative)]
    pub placement_jitter: f64,
    /// Each take its own emotion intensity, 1 ± this (0 to 0.9; default: ±0.15 by sentence);
    /// the truth of an edit is then the target emotion's average take.
    #[arg(long, default_value_t = 0.0, value_name = "SPREAD")]
    pub take_intensity: f64,
    /// Spread each emotion direction over the speech, brow and lid fields and a smooth field
    /// over the whole face, at this strength (0 to 3; 1 is about as strong as the emotion).
    #[arg(long, default_value_t = 0.0, value_name = "STRENGTH")]
    pub spread_effects: f64,
    /// Speak an emotion in only N of the sentences (drawn by the seed), e.g. angry=3.
    #[arg(long, value_name = "NAME=N", value_delimiter = ',')]
    pub takes: Vec<replay::synth::NameValue>,
    /// Each emotion shows a little differently per sentence: every take's point moves by a
    /// random offset with this standard deviation per direction (0 to 1).
    #[arg(long, default_value_t = 0.0, value_name = "STD")]
    pub interaction: f64,
    /// An emotion speaks faster or slower, e.g. angry=1.2,sad=0.85 (0.5 to 2).
    #[arg(long, value_name = "NAME=FACTOR", value_delimiter = ',')]
    pub speech_rate: Vec<replay::synth::NameValue>,
    /// File format of the takes: c3d, trc or csv.
    #[arg(long, default_value = "c3d")]
    pub format: String,
    /// Overwrite the output if it exists.
    #[arg(long)]
    pub force: bool,
}

/// `emoshift inject`.
#[derive(Debug, Args)]
pub struct InjectArgs {
    /// Real captures (.c3d, .trc or .csv) with the same markers and rate, cut in order.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Output folder (created if needed).
    #[arg(long)]
    pub out: PathBuf,
    /// Seed of the field, the cuts and the paces.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Levels of the field, each an "emotion" (level1, level2, ...).
    #[arg(long, default_value_t = crate::offline::inject::DEFAULT_LEVELS)]
    pub levels: usize,
    /// RMS of the field over the face markers at the top level, mm.
    #[arg(long, default_value_t = crate::offline::inject::DEFAULT_FIELD_MM)]
    pub field_mm: f64,
    /// Length of a sentence (a window of the captures), seconds.
    #[arg(long, default_value_t = crate::offline::inject::DEFAULT_SENTENCE_S)]
    pub sentence_s: f64,
    /// Largest move of each end of a take from its sentence's window, seconds.
    #[arg(long, default_value_t = crate::offline::inject::DEFAULT_JITTER_S)]
    pub jitter_s: f64,
    /// Largest pace change of a take (0.08: up to 8 % faster or slower).
    #[arg(long, default_value_t = crate::offline::inject::DEFAULT_PACE_SPREAD)]
    pub pace_spread: f64,
    /// Regions file of the captures' markers: copied into the session as regions.toml, where
    /// train and analyze find it, and its head_reference is the default head reference.
    #[arg(long)]
    pub regions: Option<PathBuf>,
    /// Rigid head markers whose frame the field is in: auto, none (world coordinates), or
    /// comma-separated labels or globs (default: the regions file's head_reference, else
    /// auto; chosen as train chooses it).
    #[arg(long)]
    pub head_reference: Option<String>,
    /// File format of the takes: c3d, trc or csv.
    #[arg(long, default_value = "c3d")]
    pub format: String,
    /// Overwrite the output if it exists.
    #[arg(long)]
    pub force: bool,
}
