//! The arguments of the live commands: the service, its bench, replays and the demo.
//!
//! The argument docs are clap's help text, where `[..]` marks an optional part, not a link.
#![allow(rustdoc::broken_intra_doc_links)]

use std::path::PathBuf;

use clap::Args;

/// `emoshift serve`. Flags override the config file.
#[derive(Debug, Args)]
pub struct ServeArgs {
    /// TOML config file (every flag has a key; see docs/emoshift.toml).
    #[arg(long, env = "EMOSHIFT_CONFIG")]
    pub config: Option<PathBuf>,
    /// Model file (JSON). Without one (a new performer's model does not exist yet), frames
    /// pass through unedited and can be recorded; /model/load loads one later.
    #[arg(long, env = "EMOSHIFT_MODEL")]
    pub model: Option<PathBuf>,
    /// Without a model: the rate announced and recorded for the streams passed through, Hz
    /// [default: 120].
    #[arg(long, value_name = "HZ")]
    pub passthrough_rate: Option<f64>,
    /// Frame socket, IP:PORT [default: 127.0.0.1:9000].
    #[arg(long, value_name = "IP:PORT")]
    pub listen: Option<String>,
    /// Control socket, IP:PORT [default: 127.0.0.1:9001].
    #[arg(long, value_name = "IP:PORT")]
    pub control: Option<String>,
    /// Who may send control messages (and use the monitor page's controls): networks in CIDR
    /// form, comma-separated, replacing the config's control_allow [default: loopback only].
    #[arg(long, value_name = "CIDR,...", value_delimiter = ',')]
    pub control_allow: Vec<String>,
    /// Who may send frames: networks in CIDR form, comma-separated, replacing the config's
    /// frames_allow [default: anyone].
    #[arg(long, value_name = "CIDR,...", value_delimiter = ',')]
    pub frames_allow: Vec<String>,
    /// Static subscriber HOST:PORT[:profile] (compact, flat-split, components); repeatable,
    /// replaces the config's list.
    #[arg(long, value_name = "HOST:PORT[:PROFILE]")]
    pub send: Vec<String>,
    /// Low-pass window of the emotion edit, seconds [default: 1].
    #[arg(long, value_parser = super::values::non_negative_f32)]
    pub lowpass: Option<f32>,
    /// Serve the monitor page here (a browser shows the faces, the emotion control and the
    /// health); loopback unless told otherwise. Beyond loopback it asks for a token.
    #[arg(long, value_name = "IP:PORT", num_args = 0..=1,
          default_missing_value = crate::serve::monitor::DEFAULT_MONITOR)]
    pub monitor: Option<String>,
    /// Take frames from an OptiTrack Motive NatNet server too: its command channel,
    /// IP[:PORT] [port 1510]. Each markerset becomes a stream, beside the OSC frame socket.
    #[arg(long, value_name = "SERVER[:PORT]")]
    pub natnet: Option<String>,
    /// The NatNet source's settings.
    #[command(flatten)]
    pub natnet_options: NatNetArgs,
    /// Take frames from Qualisys QTM's real-time output too: HOST[:PORT] [port 22223]. One
    /// stream of every label, or one per performer with `qtm_performers` in the config.
    #[arg(long, value_name = "HOST[:PORT]")]
    pub qtm: Option<String>,
    /// Be a NatNet server (Motive's look) for OptiTrack's Unreal, Unity and MotionBuilder
    /// plugins and NatNet clients: the command port, IP[:PORT] [default: 127.0.0.1:1510]; the
    /// data port is PORT+1. Beside Motive on one host pick other ports, e.g. 127.0.0.1:1512.
    #[arg(long, value_name = "IP:PORT", num_args = 0..=1,
          default_missing_value = crate::serve::sinks::natnet::DEFAULT_NATNET_SERVER)]
    pub natnet_server: Option<String>,
    /// Multicast the NatNet server's frames to this group, GROUP[:PORT] [239.255.42.99, the
    /// data port], instead of unicast to each client.
    #[arg(long, value_name = "GROUP[:PORT]", num_args = 0..=1, default_missing_value = "",
          requires = "natnet_server")]
    pub natnet_server_multicast: Option<String>,
    /// Local IPv4 address the NatNet server multicasts on [default: the command address's].
    #[arg(long, value_name = "IP", requires = "natnet_server")]
    pub natnet_server_interface: Option<String>,
    /// The bitstream the NatNet server streams unless a client asks for another (3.1 for
    /// Motive 2.x clients, 4.1) [default: 4.1].
    #[arg(long, value_name = "VERSION", requires = "natnet_server")]
    pub natnet_server_version: Option<String>,
    /// Also stream each performer's unedited input as a `<name>_raw` markerset (A/B).
    #[arg(long, requires = "natnet_server")]
    pub natnet_server_raw: bool,
    /// Be a QTM server (Qualisys QTM's look) for QTM Connect for Unreal, Unity and
    /// MotionBuilder and the Qualisys SDKs: the RT port, IP[:PORT] [default: 127.0.0.1:22223];
    /// discovery is answered on UDP 22226. Beside QTM on one host pick another port.
    #[arg(long, value_name = "IP:PORT", num_args = 0..=1,
          default_missing_value = crate::serve::sinks::qtm::DEFAULT_QTM_SERVER)]
    pub qtm_server: Option<String>,
}

/// The NatNet options `serve` and `record` share (each needs `--natnet`).
#[derive(Debug, Args)]
pub struct NatNetArgs {
    /// Where NatNet frames arrive: a multicast group (joined on --natnet-interface) or a
    /// local unicast address [default: what the server announces].
    #[arg(long, value_name = "ADDR:PORT", requires = "natnet")]
    pub natnet_data: Option<String>,
    /// Local IPv4 address to join the NatNet multicast group on.
    #[arg(long, value_name = "IP", requires = "natnet")]
    pub natnet_interface: Option<String>,
    /// Rate of Motive's timecode, which NatNet does not send (24, 25, 29.97df, 30, 59.94df...).
    #[arg(long, value_name = "RATE", requires = "natnet")]
    pub natnet_timecode_rate: Option<String>,
    /// NatNet marker names: asset:marker (as Motive exports them; default), asset_marker, or
    /// marker.
    #[arg(long, value_name = "STYLE", requires = "natnet")]
    pub natnet_names: Option<String>,
}

impl NatNetArgs {
    /// These options over the `natnet` keys of a config.
    pub fn raw(&self, server: Option<String>) -> crate::serve::sources::natnet::RawNatNet {
        crate::serve::sources::natnet::RawNatNet {
            server,
            data: self.natnet_data.clone(),
            interface: self.natnet_interface.clone(),
            timecode_rate: self.natnet_timecode_rate.clone(),
            names: self.natnet_names.clone(),
            ..Default::default()
        }
    }
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
    #[arg(long, default_value_t = 3.0, value_parser = super::values::positive)]
    pub seconds: f64,
    /// The daemon's `poll_window_us` (0: the processing thread always parks).
    #[arg(long, default_value_t = crate::serve::config::DEFAULT_POLL_WINDOW_US)]
    pub poll_window_us: u64,
    /// Also run every daemon round with the monitor page served here, each once a browser
    /// shows it (the rounds alternate with and without), and compare the latencies.
    #[arg(long, value_name = "IP:PORT")]
    pub monitor: Option<String>,
    /// Also feed the daemon from a NatNet server (a Motive stand-in on loopback, multicast),
    /// in rounds alternating with the OSC source and the relay: frames lost over NatNet, and
    /// its added latency against OSC's in the same run.
    #[arg(long)]
    pub natnet: bool,
    /// Also run rounds with a NatNet client on the daemon's `--natnet-server` (unicast, 4.1)
    /// beside the OSC receivers: the NatNet output's added latency against the OSC compact
    /// output's in the same run, as a ratio.
    #[arg(long)]
    pub natnet_server: bool,
    /// Also run rounds with a QTM RT client (TCP, `StreamFrames AllFrames 3D`) on the daemon's
    /// `--qtm-server` beside the OSC receivers: the QTM output's added latency against the OSC
    /// compact output's in the same run, as a ratio.
    #[arg(long)]
    pub qtm_server: bool,
}

/// `emoshift record`.
#[derive(Debug, Args)]
pub struct RecordArgs {
    /// Take OSC frames on this socket, IP:PORT (what `emoshift replay --to` or a stage bridge
    /// sends to).
    #[arg(long, value_name = "IP:PORT", conflicts_with = "natnet")]
    pub listen: Option<String>,
    /// Take frames from a NatNet server (OptiTrack Motive): its command channel, IP[:PORT].
    #[arg(long, value_name = "SERVER[:PORT]")]
    pub natnet: Option<String>,
    /// The NatNet source's settings.
    #[command(flatten)]
    pub natnet_options: NatNetArgs,
    /// Take frames from Qualisys QTM's real-time output: HOST[:PORT] [port 22223].
    #[arg(long, value_name = "HOST[:PORT]")]
    pub qtm: Option<String>,
    /// The file, .c3d, .trc or .csv.
    #[arg(long)]
    pub out: PathBuf,
    /// Replace --out if it exists.
    #[arg(long)]
    pub force: bool,
    /// Stop after this many frames (gaps included).
    #[arg(long, value_name = "N", conflicts_with = "seconds")]
    pub frames: Option<u64>,
    /// Stop after this many seconds of capture.
    #[arg(long, value_name = "S", value_parser = super::values::positive)]
    pub seconds: Option<f64>,
    /// The stream to record: a NatNet markerset (asset) name, or `IP:PORT/LAYOUT` of an OSC
    /// source [default: the first stream that arrives].
    #[arg(long, value_name = "NAME")]
    pub performer: Option<String>,
}

/// `emoshift session`.
#[derive(Debug, Args)]
pub struct SessionArgs {
    /// The session folder: takes, session.toml, script.toml, then model.json and report/.
    pub dir: PathBuf,
    /// Take OSC frames on this socket, IP:PORT (what `emoshift replay --to` or a stage bridge
    /// sends to).
    #[arg(long, value_name = "IP:PORT", conflicts_with = "natnet")]
    pub listen: Option<String>,
    /// Take frames from a NatNet server (OptiTrack Motive): its command channel, IP[:PORT].
    #[arg(long, value_name = "SERVER[:PORT]")]
    pub natnet: Option<String>,
    /// The NatNet source's settings.
    #[command(flatten)]
    pub natnet_options: NatNetArgs,
    /// Take frames from Qualisys QTM's real-time output: HOST[:PORT] [port 22223].
    #[arg(long, value_name = "HOST[:PORT]")]
    pub qtm: Option<String>,
    /// The script (TOML: `emotions = [...]` and [[sentence]] tables with `text`) [default: the
    /// Harvard sentences in neutral, happy, sad and angry].
    #[arg(long, value_name = "FILE", conflicts_with = "resume")]
    pub script: Option<PathBuf>,
    /// The stream to record: a NatNet markerset (asset) name, or `IP:PORT/LAYOUT` of an OSC
    /// source [default: the first stream that arrives].
    #[arg(long, value_name = "NAME")]
    pub performer: Option<String>,
    /// Take /session/* controls on this OSC socket, IP:PORT.
    #[arg(long, value_name = "IP:PORT")]
    pub control: Option<String>,
    /// Who may control, networks in CIDR form, comma separated [default: loopback only].
    #[arg(long, value_name = "CIDR,...", value_delimiter = ',')]
    pub control_allow: Vec<String>,
    /// The shared secret mutating controls carry as their last argument.
    #[arg(long, env = "EMOSHIFT_CONTROL_SECRET", hide_env_values = true)]
    pub control_secret: Option<String>,
    /// Continue the session in DIR where it stopped (Ctrl-C, a crash, a power cut).
    #[arg(long)]
    pub resume: bool,
    /// With --resume: record these takes again (comma separated, e.g. s03_happy,s05_sad, as
    /// finish advises); each accepted take they replace moves to DIR/replaced/.
    #[arg(
        long,
        value_name = "TAKE,...",
        value_delimiter = ',',
        requires = "resume"
    )]
    pub redo: Vec<String>,
    /// The regions file training and analysis use (copied into DIR as regions.toml).
    #[arg(long, value_name = "FILE")]
    pub regions: Option<PathBuf>,
    /// The takes' format: c3d, trc or csv.
    #[arg(long, default_value = "c3d")]
    pub format: String,
    /// Share of the model markers' samples a take must hold, 0.5 to 1.
    #[arg(long, default_value_t = crate::offline::session::check::DEFAULT_MIN_SEEN)]
    pub min_seen: f64,
    /// After finishing, send the model to a running `serve` (/model/load to its control
    /// socket, HOST:PORT) and report its answer.
    #[arg(long, value_name = "HOST:PORT")]
    pub load_into: Option<String>,
    /// Do not read controls from the keyboard (stdin).
    #[arg(long)]
    pub no_keyboard: bool,
    /// Serve the performer's view (the sentence large, the emotion, take n of N, a recording
    /// light, the markers seen, and big start/stop/retake/skip/back/finish buttons under the
    /// control rules) at this address [default: 127.0.0.1:9080].
    #[arg(long, value_name = "IP:PORT", num_args = 0..=1,
          default_missing_value = crate::serve::session::view::DEFAULT_VIEW)]
    pub monitor: Option<String>,
    /// The token the performer's view asks for (16 to 256 letters, digits or -._~) [default:
    /// none on this host's own address, a random one printed at start beyond it].
    #[arg(
        long,
        value_name = "TOKEN",
        env = "EMOSHIFT_MONITOR_TOKEN",
        hide_env_values = true
    )]
    pub monitor_token: Option<String>,
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
    #[arg(long, default_value_t = 1.0, value_parser = super::values::positive)]
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
    /// Serve the monitor page here and keep the daemon running with the take looping until
    /// Ctrl-C (prints the page's URL).
    #[arg(long, value_name = "IP:PORT", num_args = 0..=1,
          default_missing_value = crate::serve::monitor::DEFAULT_MONITOR)]
    pub monitor: Option<String>,
}
