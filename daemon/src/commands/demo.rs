//! `emoshift demo [--keep DIR] [--real]`: the whole chain on an embedded default, in a minute.
//!
//! 1. a paired synthetic session (or, with `--real`, the bundled Facial-Sing capture);
//! 2. train and analyse a model (progress and summaries as `train` and `analyze` print them);
//! 3. the daemon on loopback (ephemeral ports), in this process;
//! 4. a neutral take replayed into it at its rate while the emotion sweeps through named
//!    emotions of the model's emotion space over OSC control (no sweep without emotion pairs);
//! 5. a client subscribed with the compact profile receives the edited stream;
//! 6. a summary: frames, loss, latency percentiles, the emotion state seen, the components and
//!    their roles, and the path of the HTML report.

use std::net::{SocketAddr, UdpSocket};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use ica_core::model::IcaModel;
use protocol::{
    decode_frame_into, decode_reply, encode_control_into, encode_frame_into, encode_labels_into,
    messages, Address, Control, FrameBuf, Labels, Limits, Profile, Reply,
};
use replay::pacer::{Action, Pacer, PacerOptions};
use replay::synth::{write_session, SynthParams};
use replay::Take;
use tokio_util::sync::CancellationToken;

use crate::cli::{AnalyzeArgs, DemoArgs, TrainArgs};
use crate::serve;

/// The bundled real capture (NaturalPoint ARENA, 38 markers at 100 Hz; see
/// replay/tests/fixtures/SOURCE.md) and the regions read off its geometry.
const FACIAL_SING: &[u8] = include_bytes!("../../../replay/tests/fixtures/Facial-Sing.c3d");
const FACIAL_SING_REGIONS: &str = include_str!("../../tests/fixtures/facial-sing.regions.toml");

/// Sentences of the demo session: 8 x 4 emotions over 2 emotion directions, about 13,000
/// frames at 120 Hz.
const SENTENCES: usize = 8;
/// Seconds of live streaming (the take loops).
const STREAM_S: f64 = 12.0;

fn step(n: usize, text: &str) -> Result<()> {
    crate::out!("\n== {n}/5 {text}");
    Ok(())
}

pub(crate) fn run(args: &DemoArgs) -> Result<()> {
    let started = Instant::now();
    let (dir, temporary) = match &args.keep {
        Some(d) => (d.clone(), false),
        None => (std::env::temp_dir().join("emoshift-demo"), true),
    };
    if temporary && dir.exists() {
        std::fs::remove_dir_all(&dir).with_context(|| format!("cannot clear {}", dir.display()))?;
    }
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let result = chain(args, &dir, started);
    if temporary {
        // Only the report stays, so the path in the summary opens; the rest was scaffolding.
        for entry in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
            if entry.file_name() != "report" {
                let path = entry.path();
                let _ = if path.is_dir() {
                    std::fs::remove_dir_all(&path)
                } else {
                    std::fs::remove_file(&path)
                };
            }
        }
        if result.is_ok() {
            crate::out!(
                "(session and model were temporary; `emoshift demo --keep DIR` keeps them)"
            );
        }
    }
    result
}

/// The inputs of training and analysis, and the take to stream.
struct Session {
    manifest: PathBuf,
    regions: Option<PathBuf>,
    take: PathBuf,
    components: Option<usize>,
    sweep: Option<Vec<String>>,
}

fn chain(args: &DemoArgs, dir: &Path, started: Instant) -> Result<()> {
    let session = if args.real {
        step(
            1,
            "the bundled real capture (Facial-Sing, 38 markers at 100 Hz)",
        )?;
        real_session(dir)?
    } else {
        step(
            1,
            "a paired synthetic session (8 sentences x neutral, happy, sad, angry over 2 emotion directions)",
        )?;
        synthetic_session(dir, args.seed)?
    };
    step(2, "training the ICA model")?;
    let model_path = dir.join("model.json");
    super::train::run(&TrainArgs {
        manifest: Some(session.manifest.clone()),
        files: Vec::new(),
        out: model_path.clone(),
        variance: None,
        components: session.components,
        seed: ica_core::fit::DEFAULT_SEED,
        restarts: ica_core::fit::DEFAULT_RESTARTS,
        max_iter: ica_core::fit::DEFAULT_MAX_ITER,
        tol: ica_core::fit::DEFAULT_TOL,
        rate: None,
        max_missing: 0.5,
        max_speed: "auto".into(),
        head_reference: None,
        head_patterns: crate::offline::training::DEFAULT_HEAD_PATTERNS
            .iter()
            .map(|p| p.to_string())
            .collect(),
        regions: session.regions.clone(),
        no_bounds: false,
    })?;
    step(3, "analysing the components")?;
    let report = dir.join("report");
    super::analyze::run(&AnalyzeArgs {
        model: model_path.clone(),
        manifest: session.manifest.clone(),
        regions: session.regions.clone(),
        out: report.clone(),
        write_model: true,
    })?;
    let model = crate::offline::load_model(&model_path)?;
    let take = crate::offline::load_take(&session.take)?;
    step(4, "serving on loopback and replaying a take through it")?;
    let live = stream(&model_path, &model, &take, session.sweep.as_ref())?;
    step(5, "summary")?;
    summary(&live, &model, &take, &report.join("report.html"), started)
}

fn synthetic_session(dir: &Path, seed: u64) -> Result<Session> {
    let params = SynthParams {
        seed,
        sentences: SENTENCES,
        emotions: ["neutral", "happy", "sad", "angry"]
            .iter()
            .map(|e| e.to_string())
            .collect(),
        emotion_dims: 2,
        ..SynthParams::default()
    };
    let s = dir.join("session");
    let summary = write_session(&s, &params, replay::Format::C3d)
        .with_context(|| format!("cannot write the session to {}", s.display()))?;
    crate::out!(
        "wrote {} takes, {} frames, {} markers to {}",
        summary.takes.len(),
        summary.total_frames,
        summary.markers,
        s.display()
    );
    Ok(Session {
        manifest: summary.manifest,
        regions: None,
        take: s.join("s01_neutral.c3d"),
        components: None,
        sweep: Some(vec!["sad".into(), "happy".into(), "angry".into()]),
    })
}

fn real_session(dir: &Path) -> Result<Session> {
    let take = dir.join("Facial-Sing.c3d");
    std::fs::write(&take, FACIAL_SING)
        .with_context(|| format!("cannot write {}", take.display()))?;
    let regions = dir.join("regions.toml");
    std::fs::write(&regions, FACIAL_SING_REGIONS)?;
    let manifest = dir.join("session.toml");
    std::fs::write(
        &manifest,
        "rate_hz = 100\n\n[[take]]\nfile = \"Facial-Sing.c3d\"\nsentence = \"song\"\nemotion = \"singing\"\n",
    )?;
    crate::out!(
        "wrote {}, its regions and a one-take manifest (no emotion pairs)",
        take.display()
    );
    Ok(Session {
        manifest,
        regions: Some(regions),
        take,
        components: None,
        sweep: None,
    })
}

/// What the client saw of one frame.
#[derive(Debug, Clone)]
struct Seen {
    received: Instant,
    target: String,
    amount: f32,
    positions: Vec<f32>,
    missing: Vec<bool>,
}

/// The live run's measurements.
/// What the client saw at one frame: time (s), target, amount, and the emotion components.
type State = (f64, String, f32, Option<Vec<f32>>);

struct Live {
    sent: usize,
    received: usize,
    latencies_us: Vec<f64>,
    states: Vec<State>,
    late_sends: u64,
    sweep: Option<Vec<String>>,
}

fn stream(
    model_path: &Path,
    model: &IcaModel,
    take: &Take,
    sweep: Option<&Vec<String>>,
) -> Result<Live> {
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .context("cannot start the runtime")?;
    let config = serve::config::RawConfig {
        listen: Some("127.0.0.1:0".into()),
        control: Some("127.0.0.1:0".into()),
        model: Some(model_path.to_path_buf()),
        ..Default::default()
    }
    .validate()?;
    let bound = runtime.block_on(serve::bind_with(config, model.clone()))?;
    let (frames_to, control_to) = (bound.frame_addr()?, bound.control_addr()?);
    crate::out!("daemon: frames on {frames_to}, control on {control_to}");
    let shutdown = CancellationToken::new();
    let server = runtime.spawn(bound.run(shutdown.clone()));

    // Frames arrive on `client`; control replies on `ctl`, so neither reader steals the other's.
    let client = UdpSocket::bind("127.0.0.1:0")?;
    client.set_read_timeout(Some(Duration::from_millis(100)))?;
    let ctl = UdpSocket::bind("127.0.0.1:0")?;
    ctl.set_read_timeout(Some(Duration::from_millis(100)))?;
    let port = client.local_addr()?.port();
    control(
        &ctl,
        control_to,
        &Control::Subscribe {
            port,
            profile: Profile::Compact,
        },
    )?;
    crate::out!("client: subscribed 127.0.0.1:{port} with the compact profile");

    let seen: Arc<Mutex<Vec<(i32, Seen)>>> = Arc::new(Mutex::new(Vec::new()));
    let stop = Arc::new(AtomicBool::new(false));
    let receiver = {
        let (seen, stop, socket) = (seen.clone(), stop.clone(), client.try_clone()?);
        let markers = model.markers().max(1);
        std::thread::spawn(move || receive(&socket, &seen, &stop, markers))
    };
    let sent = send_take(take, frames_to, &ctl, control_to, sweep)?;
    std::thread::sleep(Duration::from_millis(300));
    stop.store(true, Ordering::Relaxed);
    let _ = receiver.join();
    shutdown.cancel();
    runtime.block_on(server).context("server task")??;

    let seen = seen
        .lock()
        .map_err(|_| anyhow::anyhow!("receiver panicked"))?;
    let mut latencies_us = Vec::new();
    let mut states = Vec::new();
    let start = sent.first_send;
    // The emotion components of what the client received, to show the sweep in model units.
    let mut processor = crate::engine::frame::FrameProcessor::new(model);
    let mut u = vec![0.0f32; model.components()];
    let space = model.emotion().space_components();
    for (number, s) in seen.iter() {
        if let Some(at) = sent.sent_at.get(&(*number as i64)) {
            latencies_us.push(s.received.duration_since(*at).as_secs_f64() * 1e6);
        }
        let value = match space.is_empty() {
            false if s.missing.len() == model.markers() => processor
                .project(&s.positions, &s.missing, &mut u)
                .ok()
                .map(|_| space.iter().map(|&k| u[k]).collect::<Vec<f32>>()),
            _ => None,
        };
        let t = s.received.duration_since(start).as_secs_f64();
        states.push((t, s.target.clone(), s.amount, value));
    }
    Ok(Live {
        sent: sent.sent_at.len(),
        received: seen.len(),
        latencies_us,
        states,
        late_sends: sent.late,
        sweep: sweep.cloned(),
    })
}

/// Sends one control message from the client socket and waits for its confirmation.
fn control(socket: &UdpSocket, to: SocketAddr, msg: &Control) -> Result<()> {
    let mut out = Vec::new();
    encode_control_into(msg, &mut out);
    socket.send_to(&out, to)?;
    let deadline = Instant::now() + Duration::from_secs(2);
    let mut buf = vec![0u8; 65_536];
    while Instant::now() < deadline {
        let Ok((n, from)) = socket.recv_from(&mut buf) else {
            continue;
        };
        if from != to {
            continue;
        }
        match decode_reply(&buf[..n]) {
            Ok(Reply::Confirm(_)) => return Ok(()),
            Ok(Reply::Error { address, message }) => bail!("daemon refused {address}: {message}"),
            _ => continue,
        }
    }
    bail!("the daemon did not confirm {:?} within 2 s", msg)
}

/// What the sender did.
struct Sent {
    sent_at: std::collections::HashMap<i64, Instant>,
    first_send: Instant,
    late: u64,
}

/// Replays `take` at its rate on the pacer's deadlines; sweeps the emotion half way.
fn send_take(
    take: &Take,
    to: SocketAddr,
    client: &UdpSocket,
    control_to: SocketAddr,
    sweep: Option<&Vec<String>>,
) -> Result<Sent> {
    let socket = UdpSocket::bind("127.0.0.1:0")?;
    let mut labels = Vec::new();
    encode_labels_into(
        &Labels {
            layout_id: 0,
            names: take.labels.clone(),
        },
        &mut labels,
    )?;
    let frames = take.n_frames();
    let duration_s = (frames as f64 / take.rate_hz).max(STREAM_S);
    if let Some(targets) = sweep {
        // Glide towards each target in turn, one equal share of the stream each.
        let share = duration_s / targets.len().max(1) as f64;
        control(client, control_to, &Control::Ramp(share as f32))?;
        control(client, control_to, &Control::Target(targets[0].clone()))?;
        control(client, control_to, &Control::Amount(1.0))?;
        crate::out!(
            "sweep: towards {} in turn, {share:.1} s each",
            targets.join(", then ")
        );
    }
    let options = PacerOptions {
        first_frame_number: take.first_frame,
        looping: true,
        ..PacerOptions::default()
    };
    // With a sweep, loop the take for at least STREAM_S; without one, stream the take (capped).
    let stream_frames = (STREAM_S * take.rate_hz).ceil() as usize;
    let total = if sweep.is_some() {
        stream_frames.max(frames)
    } else {
        stream_frames.min(frames)
    };
    let mut pacer = Pacer::new(take.rate_hz, frames, options)?;
    let mut buf = FrameBuf::with_max_markers(take.n_markers());
    let mut datagram = Vec::with_capacity(protocol::frame_message_len(take.n_markers()));
    let mut sent_at = std::collections::HashMap::with_capacity(frames);
    let origin = Instant::now();
    let mut next_target = 1usize;
    loop {
        match pacer.poll(origin.elapsed()) {
            Action::SendLabels => {
                socket.send_to(&labels, to)?;
            }
            Action::SendFrame(f) => {
                if f.stream_index as usize >= total {
                    break;
                }
                if let Some(targets) = sweep {
                    let at = next_target * total / targets.len().max(1);
                    if next_target < targets.len() && f.stream_index as usize >= at {
                        let target = targets[next_target].clone();
                        control(client, control_to, &Control::Target(target))?;
                        next_target += 1;
                    }
                }
                buf.set_frame(
                    f.frame_number as i32,
                    f.capture_time_us,
                    take.frame(f.index),
                )?;
                for (m, &gone) in take.frame_missing(f.index).iter().enumerate() {
                    buf.set_missing(m, gone);
                }
                encode_frame_into(&buf, &mut datagram)?;
                sent_at.insert(f.frame_number, Instant::now());
                socket.send_to(&datagram, to)?;
            }
            Action::Sleep { until } => {
                let wait = until.saturating_sub(origin.elapsed());
                std::thread::sleep(wait.saturating_sub(Duration::from_micros(200)));
                while origin.elapsed() < until {
                    std::hint::spin_loop();
                }
            }
            Action::Done => break,
        }
    }
    Ok(Sent {
        sent_at,
        first_send: origin,
        late: pacer.summary().late_frames,
    })
}

/// Receives the compact profile until `stop`: frame numbers with their arrival time and the
/// emotion state that came with them.
fn receive(socket: &UdpSocket, seen: &Mutex<Vec<(i32, Seen)>>, stop: &AtomicBool, markers: usize) {
    let mut buf = vec![0u8; 65_536];
    let mut frame = FrameBuf::with_max_markers(markers);
    let limits = Limits::default();
    while !stop.load(Ordering::Relaxed) {
        let Ok((n, _)) = socket.recv_from(&mut buf) else {
            continue;
        };
        let received = Instant::now();
        let Ok(msgs) = messages(&buf[..n], &limits) else {
            continue;
        };
        let (mut number, mut target, mut amount) = (None, String::new(), 0.0);
        let (mut positions, mut missing) = (Vec::new(), Vec::new());
        for m in msgs {
            match Address::parse(m.address) {
                Some(Address::Frame) => {
                    if let Ok(h) = decode_frame_into(m.bytes, &mut frame) {
                        number = Some(h.frame_number);
                        // The demo's client keeps what it saw; a real client would not.
                        positions = frame.positions().to_vec();
                        missing = (0..h.marker_count).map(|i| frame.is_missing(i)).collect();
                    }
                }
                Some(Address::State) => {
                    if let Ok(state) = protocol::decode_state(m.bytes) {
                        target = state.target.to_string();
                        amount = state.amount;
                    }
                }
                _ => {}
            }
        }
        if let (Some(number), Ok(mut seen)) = (number, seen.lock()) {
            seen.push((
                number,
                Seen {
                    received,
                    target,
                    amount,
                    positions,
                    missing,
                },
            ));
        }
    }
}

fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

fn summary(
    live: &Live,
    model: &IcaModel,
    take: &Take,
    report: &Path,
    started: Instant,
) -> Result<()> {
    let mut lat = live.latencies_us.clone();
    lat.sort_by(f64::total_cmp);
    let lost = live.sent.saturating_sub(live.received);
    crate::out!(
        "frames: {} sent at {} Hz, {} received, {} lost ({:.2} %), {} sent late",
        live.sent,
        take.rate_hz,
        live.received,
        lost,
        100.0 * lost as f64 / live.sent.max(1) as f64,
        live.late_sends
    );
    crate::out!(
        "latency source -> daemon -> client: p50 {:.0} us, p99 {:.0} us, p99.9 {:.0} us, max {:.0} us",
        percentile(&lat, 0.5),
        percentile(&lat, 0.99),
        percentile(&lat, 0.999),
        percentile(&lat, 1.0)
    );
    if let Some(targets) = &live.sweep {
        let space: Vec<String> = model
            .emotion()
            .space_components()
            .iter()
            .map(|k| format!("c{k}"))
            .collect();
        crate::out!(
            "emotion sweep {} as the client saw it (emotion components {} of the received markers, 0.5 s means):",
            targets.join(" -> "),
            space.join(" ")
        );
        let end = live.states.last().map_or(0.0, |s| s.0);
        let mut t0 = 0.0;
        while t0 < end {
            let window: Vec<&State> = live
                .states
                .iter()
                .filter(|s| s.0 >= t0 && s.0 < t0 + 0.5)
                .collect();
            let values: Vec<&Vec<f32>> = window.iter().filter_map(|s| s.3.as_ref()).collect();
            if let (Some(last), false) = (window.last(), values.is_empty()) {
                let dims = values[0].len();
                let mean: Vec<String> = (0..dims)
                    .map(|j| {
                        let m = values.iter().map(|v| v[j]).sum::<f32>() / values.len() as f32;
                        format!("{m:+.3}")
                    })
                    .collect();
                crate::out!(
                    "  t {t0:4.1}-{:4.1} s  target {:<10} amount {:.2}  emotion {}",
                    t0 + 0.5,
                    last.1,
                    last.2,
                    mean.join(" ")
                );
            }
            t0 += 0.5;
        }
    }
    crate::out!("components:");
    for (k, role) in model.roles().iter().enumerate() {
        crate::out!(
            "  c{k}: {:<9} |M_k| {:.2} mm",
            format!("{role:?}").to_lowercase(),
            model.mixing().column(k).norm()
        );
    }
    let e = model.emotion();
    for name in e.names() {
        if let Some(point) = e.point(&name) {
            let p: Vec<String> = point.iter().map(|v| format!("{v:+.3}")).collect();
            crate::out!("  emotion {name}: {}", p.join(" "));
        }
    }
    crate::out!("report: {}", report.display());
    crate::out!("demo finished in {:.1} s", started.elapsed().as_secs_f64());
    if live.received == 0 {
        bail!("the client received no frame from the daemon");
    }
    Ok(())
}
