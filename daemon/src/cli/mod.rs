//! The command line: one clap-derive enum of subcommands, each a thin front end.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

mod live;
mod offline;
mod range;
mod sessions;
mod values;

pub use live::{
    BenchArgs, DemoArgs, NatNetArgs, RecordArgs, ReplayArgs, ServeArgs, SessionArgs, WireFormat,
};
pub use offline::{
    AnalyzeArgs, ConvertArgs, EditArgs, InfoArgs, InspectArgs, KeyValue, ProjectArgs, TrainArgs,
};
pub use range::RangeArgs;
pub use sessions::{InjectArgs, SynthArgs};

/// A command-line error on one line, as every other failure is: clap's message with its
/// indented details joined on, then where to look.
pub fn one_line(error: &clap::Error) -> String {
    let text = error.render().to_string();
    let message: Vec<&str> = text
        .lines()
        .take_while(|l| !l.trim().is_empty())
        .map(str::trim)
        .collect();
    let message = message.join(" ");
    let message = message.strip_prefix("error: ").unwrap_or(&message);
    format!("{message} (see --help)")
}

/// emoshift: edit the emotion of facial motion capture, offline and live.
#[derive(Debug, Parser)]
#[command(name = "emoshift", version, about, long_about = None)]
pub struct Cli {
    /// Largest input file read (takes, models, manifests), MB; devices and FIFOs are refused
    /// whatever their size.
    #[arg(
        long,
        global = true,
        default_value_t = 8192,
        value_name = "MB",
        value_parser = values::input_limit_mb
    )]
    pub max_input_mb: u64,
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
    /// Cut real captures into a paired session with a known signal: each level of a smooth
    /// field, added in head coordinates, is an "emotion" (truth in truth/inject.json).
    #[command(
        after_help = "Examples:\n  emoshift inject Facial-Sing.c3d --out sing --seed 3\n  \
        emoshift inject JawMoCap.c3d EyebrowsMoCap.c3d --out anim --head-reference ForeHead_M,ForeHead_L,ForeHead_R,NoseTop\n\n\
        Then: emoshift train --manifest sing/session.toml --out sing/model.json; emoshift analyze \
        --model sing/model.json --manifest sing/session.toml --regions REGIONS --out sing/report \
        --write-model; emoshift edit ... --to-emotion level3."
    )]
    Inject(InjectArgs),
    /// Show a take's labels, rate, frame range, units and missing samples per marker.
    #[command(after_help = "Examples:\n  emoshift info take.c3d\n  emoshift info take.trc --json")]
    Info(InfoArgs),
    /// Recover a take cut off by a crash: make its header count every whole frame its data
    /// holds and drop a frame cut off mid-write.
    #[command(
        after_help = "Examples:\n  emoshift repair live.c3d\n  emoshift repair live.trc --out live-repaired.trc\n\n\
        `emoshift info` says when a take needs it (\"holds 363 frames, header says 1\")."
    )]
    Repair(RepairArgs),
    /// Propose a regions.toml (mouth, eyebrows, eyelids, head reference) from a take's marker
    /// names and geometry, a comment on each line saying why; check it, then analyze.
    #[command(
        after_help = "Example:\n  emoshift regions session/s01_neutral.c3d --out session/regions.toml"
    )]
    Regions(RegionsArgs),
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
    /// Capture a take from a live source (OSC or a NatNet server) to C3D, TRC or CSV, with its
    /// labels, rate, gaps and timecode; Ctrl-C leaves the file complete.
    #[command(
        after_help = "Examples:\n  emoshift record --listen 127.0.0.1:9000 --out take.c3d --seconds 30\n  \
        emoshift record --natnet 192.168.0.106 --out face.csv --performer Face --frames 3600\n  \
        emoshift record --natnet 10.0.0.5:1510 --natnet-data 239.255.42.99:1511 \
        --natnet-interface 10.0.0.20 --natnet-timecode-rate 29.97df --out take.trc"
    )]
    Record(RecordArgs),
    /// A new performer's paired calibration session from a live source: prompts for each
    /// sentence in each emotion, records and checks every take, writes session.toml as it
    /// goes (--resume continues it), then trains and analyses.
    #[command(
        after_help = "Examples:\n  emoshift session perf1 --listen 127.0.0.1:9000 --regions regions.toml\n  \
        emoshift session perf1 --natnet 192.168.0.106 --performer Face --control 127.0.0.1:9101\n  \
        emoshift session perf1 --listen 127.0.0.1:9000 --resume --load-into 127.0.0.1:9001\n\n\
        Keys: Enter starts/stops a take, t retake, s skip, b back, f finish, ? status."
    )]
    Session(SessionArgs),
    /// Run the whole chain on an embedded default: synth, train, analyze, serve, replay with an
    /// emotion sweep, receive, summarise.
    #[command(
        after_help = "Examples:\n  emoshift demo\n  emoshift demo --keep demo-out\n  emoshift demo --real"
    )]
    Demo(DemoArgs),
}

/// `emoshift repair`.
#[derive(Debug, Args)]
pub struct RepairArgs {
    /// The take cut off by a crash (.c3d, .trc or .csv); repaired in place unless --out.
    pub file: PathBuf,
    /// Write the repaired take here instead, leaving FILE as it is.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Overwrite --out if it exists.
    #[arg(long)]
    pub force: bool,
}

/// `emoshift regions`.
#[derive(Debug, clap::Args)]
pub struct RegionsArgs {
    /// A take of the performer (.c3d, .trc or .csv).
    pub take: PathBuf,
    /// Where to write the proposal.
    #[arg(long, default_value = "regions.toml")]
    pub out: PathBuf,
    /// Overwrite the output if it exists.
    #[arg(long)]
    pub force: bool,
}
