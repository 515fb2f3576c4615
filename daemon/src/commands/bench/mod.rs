//! `emoshift bench`: the daemon against a plain UDP relay on loopback, in one run.
//!
//! 1. Paced: N senders at 120 Hz, K receivers, through the daemon and through a minimal relay
//!    (receive, send the same bytes to every receiver), alternating in rounds of a second.
//!    Each frame carries its send time in the capture-time field, which the daemon keeps, so a
//!    receiver measures the whole path. The daemon's `/status` tells its own stage latencies.
//! 2. Max rate: one sender at 50,000 frames/s through the daemon to one receiver: loss, and
//!    where frames went (from `/status`).
//! 3. One processing thread: frames through [`Pipeline`] back to back (109 markers, m = 20).
//!
//! With `--monitor IP:PORT`, every round also runs the daemon with the monitor page served
//! there, once a browser shows it (the page reconnects to each round's daemon), and prints its
//! latencies against the rounds without it.
//!
//! With `--natnet`, NatNet sources join the paced rounds: the same performers as markersets
//! of a Motive stand-in's NatNet stream ([`natnet`]), multicast (Motive's default; the kernel's
//! multicast loopback is part of the path) and unicast, each compared with the OSC source
//! measured in the same run.
//!
//! With `--natnet-server` and `--qtm-server`, rounds with a NatNet client on the daemon's
//! NatNet server, or a QTM RT client on its QTM server, beside the OSC receivers
//! ([`server_outputs`]), interleaved with the other rounds: each output's latency against the
//! OSC compact output's from the same frames.
//!
//! Bounded in time, only 127.0.0.1.

mod harness;
mod natnet;
mod qtm_client;
mod rounds;
mod server_outputs;

use std::net::SocketAddr;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use engine::pipeline::{Pipeline, PipelineConfig};
use engine::synthetic::{frame_into, labels_datagram, random_model};
use ica_core::model::IcaModel;
use protocol::{encode_frame_into, FrameBuf, Profile};

use crate::cli::BenchArgs;
use crate::serve::sinks::osc::encode::{EncodeOnly, Profiles};
use crate::serve::sources::osc::OscDemux;
use crate::serve::sources::InputCounters;
use harness::{through_daemon, through_relay, Run};
use rounds::{median_range, ratios};
use server_outputs::ServerOutput;

const MARKERS: usize = 109;
const COMPONENTS: usize = 20;
const MAX_RATE_HZ: f64 = 50_000.0;
/// The daemon and the relay alternate in rounds of at most this long, so that a change in
/// the machine's load during the run falls on both alike.
const ROUND: Duration = Duration::from_secs(1);

pub(crate) fn run(args: &BenchArgs) -> Result<()> {
    if args.performers == 0 || args.clients == 0 || !(args.seconds > 0.0 && args.seconds <= 60.0) {
        return Err(crate::exit::UsageError(
            "--performers and --clients must be at least 1, --seconds in (0, 60]".into(),
        )
        .into());
    }
    let model = random_model(MARKERS, COMPONENTS, 1);
    // Senders and receivers on one thread; the daemon and the relay each on their own.
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("starting the tokio runtime")?;
    let r = runtime.block_on(measure(&model, args))?;
    let k = args.clients;
    print_paced(args, &r)?;
    for (nn, how) in r.over_natnet.iter().zip(["multicast", "unicast"]) {
        if let Some(nn) = nn {
            print_natnet(nn, how, (&r.daemon, &r.relay), k)?;
        }
    }
    for (server, name) in r
        .servers
        .iter()
        .zip(["natnet server (unicast 4.1)", "qtm server (tcp)"])
    {
        if let Some((osc, seen)) = server {
            print_server_output(osc, seen, k, name)?;
        }
    }
    if let Some(watched) = &r.watched {
        print_watched(&r.daemon, watched, k)?;
    }
    print_max_rate(&r.max)?;
    let (per_frame_us, fps) = processing_rate(&model)?;
    crate::out!(
        "processing: {per_frame_us:.2} µs/frame median over batches, {fps:.0} frames/s on one thread"
    );
    Ok(())
}

/// What the timed runs measured.
struct Measured {
    /// The daemon, paced, every round.
    daemon: Run,
    /// The plain relay, paced, every round.
    relay: harness::Seen,
    /// The daemon with the monitor page open, every round.
    watched: Option<Run>,
    /// The daemon fed over NatNet, multicast and unicast, every round.
    over_natnet: [Option<Run>; 2],
    /// The daemon with a NatNet server client, and with a QTM server client, beside the OSC
    /// receivers, every round.
    servers: [Option<(Run, harness::Seen)>; 2],
    /// The daemon at the maximum rate.
    max: Run,
    /// Each paced round's p50 and p99 ratios, daemon over relay.
    round_ratios: Vec<[f64; 2]>,
}

/// The paced rounds (daemon and relay alternating, with the NatNet and monitor variants when
/// asked), then the maximum rate.
async fn measure(model: &IcaModel, args: &BenchArgs) -> Result<Measured> {
    let rounds = (args.seconds / ROUND.as_secs_f64()).ceil().max(1.0) as u32;
    let per_round = Duration::from_secs_f64(args.seconds) / rounds;
    let (n, k, w) = (args.performers, args.clients, args.poll_window_us);
    let monitor = args.monitor.as_deref();
    let mut daemon = through_daemon(model, (n, k), 120.0, per_round, w, None).await?;
    let mut relay = through_relay(model, n, k, per_round).await?;
    let mut round_ratios = vec![ratios(&daemon.seen, &relay)];
    let mut watched: Option<Run> = None;
    let mut over_natnet: [Option<Run>; 2] = [None, None];
    let mut servers: [Option<(Run, harness::Seen)>; 2] = [None, None];
    let outputs = [
        (ServerOutput::NatNet, args.natnet_server),
        (ServerOutput::Qtm, args.qtm_server),
    ];
    for round in 0..rounds {
        for ((output, asked), all) in outputs.into_iter().zip(servers.iter_mut()) {
            if asked {
                let r = server_outputs::through_daemon_server(model, (n, k), per_round, w, output);
                add_pair(all, r.await?);
            }
        }
        for (multicast, all) in [true, false].into_iter().zip(over_natnet.iter_mut()) {
            if !args.natnet {
                break;
            }
            let r = natnet::through_daemon_natnet(model, (n, k), per_round, w, multicast).await?;
            match all.as_mut() {
                None => *all = Some(r),
                Some(all) => Run::add(all, r),
            }
        }
        if monitor.is_some() {
            let run = through_daemon(model, (n, k), 120.0, per_round, w, monitor).await?;
            match watched.as_mut() {
                None => watched = Some(run),
                Some(all) => all.add(run),
            }
        }
        if round + 1 < rounds {
            let d = through_daemon(model, (n, k), 120.0, per_round, w, None).await?;
            let r = through_relay(model, n, k, per_round).await?;
            round_ratios.push(ratios(&d.seen, &r));
            daemon.add(d);
            relay.add(&r);
        }
    }
    let one = Duration::from_secs(1);
    let max = through_daemon(model, (1, 1), MAX_RATE_HZ, one, w, None).await?;
    Ok(Measured {
        daemon,
        relay,
        watched,
        over_natnet,
        servers,
        max,
        round_ratios,
    })
}

/// The paced rounds: what came through, the daemon's own stages, and its added latency
/// against the relay's.
fn print_paced(args: &BenchArgs, r: &Measured) -> Result<()> {
    let (daemon, relay) = (&r.daemon, &r.relay);
    let sent = daemon.sent * args.clients as u64;
    crate::out!(
        "paced: {} performers x 120 Hz, {} clients, {} s, {MARKERS} markers, m = {COMPONENTS}",
        args.performers,
        args.clients,
        args.seconds
    );
    for (name, s) in [("daemon", &daemon.seen), ("relay", relay)] {
        crate::out!("  {name}: {} of ~{sent} datagrams received", s.received);
    }
    crate::out!(
        "  inside the daemon (last round): received -> processed p50 {} µs, p99 {} µs; \
         processed -> sent p50 {} µs, p99 {} µs",
        daemon.get("processed_p50_us"),
        daemon.get("processed_p99_us"),
        daemon.get("sent_p50_us"),
        daemon.get("sent_p99_us"),
    );
    crate::out!(
        "  frames caught by polling around the beat (last round): {} of {} windows",
        daemon.get("poll_hits"),
        daemon.get("poll_hits") + daemon.get("poll_misses"),
    );
    for (label, q) in [("p50", 0.5), ("p99", 0.99), ("p99.9", 0.999), ("max", 1.0)] {
        let d = daemon.seen.latency_us.value_at_quantile(q);
        let r = relay.latency_us.value_at_quantile(q);
        crate::out!(
            "{label} added latency: {d} µs (relay {r} µs, ratio {:.2}x)",
            d as f64 / r.max(1) as f64
        );
    }
    for (i, label) in ["p50", "p99"].into_iter().enumerate() {
        let (median, lo, hi) = median_range(r.round_ratios.iter().map(|x| x[i]).collect());
        crate::out!(
            "{label} ratio to the relay, median of {} interleaved rounds: {median:.2}x \
             ({lo:.2}-{hi:.2}x)",
            r.round_ratios.len()
        );
    }
    Ok(())
}

/// The NatNet rounds: loss, and added latency against the OSC rounds and the relay.
fn print_natnet(
    nn: &Run,
    how: &str,
    (osc, relay): (&Run, &harness::Seen),
    clients: usize,
) -> Result<()> {
    let expected = nn.sent * clients as u64;
    crate::out!(
        "natnet (Motive stand-in, {how} on loopback): {} of {expected} datagrams received, \
         {} lost; bad natnet datagrams (last round) {}",
        nn.seen.received,
        expected.saturating_sub(nn.seen.received),
        nn.get("natnet/bad_datagrams"),
    );
    for (label, q) in [("p50", 0.5), ("p99", 0.99), ("p99.9", 0.999), ("max", 1.0)] {
        let n = nn.seen.latency_us.value_at_quantile(q);
        let o = osc.seen.latency_us.value_at_quantile(q);
        let r = relay.latency_us.value_at_quantile(q);
        crate::out!(
            "{label} added latency over natnet {how}: {n} µs (osc {o} µs, ratio {:.2}x; relay \
             {r} µs, ratio {:.2}x)",
            n as f64 / o.max(1) as f64,
            n as f64 / r.max(1) as f64
        );
    }
    Ok(())
}

/// Adds a round's OSC run and server client to the rounds before.
fn add_pair(all: &mut Option<(Run, harness::Seen)>, (osc, seen): (Run, harness::Seen)) {
    match all.as_mut() {
        None => *all = Some((osc, seen)),
        Some(all) => {
            all.0.add(osc);
            all.1.add(&seen);
        }
    }
}

/// A server output's client against the OSC compact receivers of the same runs.
fn print_server_output(osc: &Run, seen: &harness::Seen, clients: usize, name: &str) -> Result<()> {
    crate::out!(
        "{name}, beside {clients} OSC compact receivers: {} of {} frames received; osc {} of ~{}",
        seen.received,
        osc.sent,
        osc.seen.received,
        osc.sent * clients as u64,
    );
    for (label, q) in [("p50", 0.5), ("p99", 0.99), ("p99.9", 0.999), ("max", 1.0)] {
        let n = seen.latency_us.value_at_quantile(q);
        let o = osc.seen.latency_us.value_at_quantile(q);
        crate::out!(
            "{label} added latency of the {name} output: {n} µs (osc compact, same run, {o} µs, \
             ratio {:.2}x)",
            n as f64 / o.max(1) as f64
        );
    }
    Ok(())
}

/// The rounds with the monitor page open against the rounds without, same run.
fn print_watched(daemon: &Run, watched: &Run, clients: usize) -> Result<()> {
    crate::out!(
        "with the monitor page open: {} of ~{} datagrams received; page feed dropped {}, \
         snapshots unpublished {}",
        watched.seen.received,
        watched.sent * clients as u64,
        watched.get("monitor_dropped"),
        watched.get("monitor_unpublished"),
    );
    for (label, q) in [("p50", 0.5), ("p99", 0.99), ("p99.9", 0.999)] {
        let with = watched.seen.latency_us.value_at_quantile(q);
        let without = daemon.seen.latency_us.value_at_quantile(q);
        crate::out!(
            "{label} added latency with the page open: {with} µs (without {without} µs, ratio {:.2}x)",
            with as f64 / without.max(1) as f64
        );
    }
    Ok(())
}

/// Where the frames of the max-rate run went, stage by stage.
fn print_max_rate(max: &Run) -> Result<()> {
    let received = max.seen.received as i64;
    let frames_in = max.get("frames_in");
    let warmup = harness::warmup_frames(MAX_RATE_HZ) as i64;
    let not_sent = max.get("dropped_send_buffer") + max.get("send_errors");
    crate::out!(
        "max rate: {} frames sent at {MAX_RATE_HZ} /s, {received} received, loss {:.3}%",
        max.sent,
        100.0 * (1.0 - received as f64 / max.sent.max(1) as f64)
    );
    crate::out!(
        "  lost at the daemon's socket {}, dropped in the daemon {} (queue full {}, stale {}), \
         not sent {}, lost at the receiver's socket {}",
        // The source counts a frame in as it decodes it; the daemon's counts include the
        // warm-up frames (one performer, one client), which the receiver does not count, and
        // its datagrams the labels, which are not frames.
        max.sent as i64 + warmup - frames_in,
        frames_in - max.get("frames_out"),
        max.get("frames_dropped"),
        max.get("dropped_stale"),
        not_sent,
        max.get("frames_out") - warmup - not_sent - received,
    );
    Ok(())
}

/// Frames through the processing thread's path back to back (the OSC demux, one
/// [`Pipeline`], the compact profile encoded): median µs/frame over batches, frames/s.
fn processing_rate(model: &IcaModel) -> Result<(f64, f64)> {
    let model = Arc::new(model.clone());
    let mut pipeline = Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default());
    let mut demux = OscDemux::new(MARKERS, Arc::new(InputCounters::named("osc")));
    let mut compact = EncodeOnly::new(Profiles::default().with(Profile::Compact), MARKERS);
    let mut frame_path = |d: &[u8]| {
        demux.handle_datagram(peer_addr(), d, &mut |f| {
            pipeline.handle_frame(f, &mut compact)
        });
    };
    let mut d = labels_datagram(&model)?;
    frame_path(&d);
    let mut xyz = vec![0.0f32; MARKERS * 3];
    frame_into(&model, 3, &mut xyz);
    let mut buf = FrameBuf::with_max_markers(MARKERS);
    buf.set_frame(0, 0, &xyz)?;
    encode_frame_into(&buf, &mut d)?;
    let (batch, batches) = (2_000usize, 25usize);
    let mut per_frame = Vec::with_capacity(batches);
    let mut n: i32 = 0;
    let start = Instant::now();
    for _ in 0..batches {
        let t = Instant::now();
        for _ in 0..batch {
            n += 1;
            // frame number: after "/mocap/frame\0..." (16) and ",ihbb\0\0\0" (8)
            d[24..28].copy_from_slice(&n.to_be_bytes());
            frame_path(&d);
        }
        per_frame.push(t.elapsed().as_secs_f64() * 1e6 / batch as f64);
    }
    let total = start.elapsed().as_secs_f64();
    per_frame.sort_by(f64::total_cmp);
    if pipeline.counters.frames_out != (batch * batches) as u64 {
        anyhow::bail!(
            "the pipeline dropped frames: {} of {} out",
            pipeline.counters.frames_out,
            batch * batches
        );
    }
    Ok((per_frame[batches / 2], (batch * batches) as f64 / total))
}

/// The source address of [`processing_rate`]'s frames.
fn peer_addr() -> SocketAddr {
    SocketAddr::from(([127, 0, 0, 1], 9))
}
