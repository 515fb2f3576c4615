//! What the processing thread runs, put together from the config: the engine over the models
//! (or without one: frames pass through), every output, its OSC intake; and what control
//! shares with it.

use std::sync::{Arc, Mutex};

use anyhow::Result;
use engine::pipeline::{Pipeline, PipelineConfig};
use engine::Performer;
use ica_core::model::IcaModel;
use tokio::net::UdpSocket;
use tokio_util::sync::CancellationToken;
use tokio_util::task::TaskTracker;

use crate::serve::command::Request;
use crate::serve::control::{ControlCtx, Guard};
use crate::serve::processing::Shared;
use crate::serve::sources::osc::OscIntake;
use crate::serve::sources::{Answer, InputCounters};
use crate::serve::stats::Stats;
use crate::serve::wake::Doorbell;

use crate::serve::monitor::Feed;
use crate::serve::sinks::natnet::NatNetSink;
use crate::serve::sinks::osc::{OscOutput, OscOutputConfig};
use crate::serve::sinks::qtm::QtmSink;
use crate::serve::sinks::recording::Recorder;
use crate::serve::sinks::Outputs;
use crate::serve::Config;

/// The engine over the models (without a default model, it passes frames through).
pub(super) fn processing_pipeline(
    model: Option<Arc<IcaModel>>,
    performers: Vec<Performer>,
    config: &Config,
) -> Pipeline {
    let settings = PipelineConfig {
        lowpass_s: config.lowpass_s,
        passthrough_rate_hz: config.passthrough_rate_hz,
        ..PipelineConfig::default()
    };
    match model {
        Some(model) => Pipeline::new(model, performers, settings),
        None => Pipeline::without_model(performers, settings),
    }
}

/// Every output: the OSC subscribers, the session recording, the monitor feed when the page
/// is served, the NatNet server when configured. A new sink is one more line here.
pub(super) fn outputs(
    config: &Config,
    feed: Option<Feed>,
    (natnet, qtm): (Option<NatNetSink>, Option<QtmSink>),
    control_news: std::net::UdpSocket,
) -> Result<Outputs> {
    let osc = OscOutput::new(&OscOutputConfig {
        send: config.send.clone(),
        max_subscribers: config.max_subscribers,
        max_send_failures: config.max_send_failures,
        lease: config.lease,
        max_markers: PipelineConfig::default().max_markers,
        vmc_names: config.vmc_names.clone(),
    })?;
    let mut others: Vec<Box<dyn engine::Sink + Send>> = Vec::new();
    if let Some(natnet) = natnet {
        others.push(Box::new(natnet));
    }
    if let Some(qtm) = qtm {
        others.push(Box::new(qtm));
    }
    if let Some(feed) = feed {
        others.push(Box::new(feed));
    }
    Ok(Outputs {
        osc,
        recorder: Recorder::new().telling(control_news),
        others,
    })
}

/// The frame socket's intake: `frames_allow`, refusals answered from the socket's clone
/// `replies`.
pub(super) fn osc_intake(
    config: &Config,
    shared: &Shared,
    replies: std::net::UdpSocket,
    counters: Arc<InputCounters>,
    max_markers: usize,
) -> OscIntake {
    let allow = (config.frames_allow.clone(), Arc::clone(&shared.not_allowed));
    let answer = Arc::new(Answer::new(Some(replies)));
    OscIntake::new(allow, answer, counters, max_markers)
}

/// What the control task (and the monitor page) share: the socket, the way to the processing
/// thread, the stats, the models and the guard.
pub(super) fn control_ctx(
    socket: UdpSocket,
    (cmd_tx, bell): (crossbeam_channel::Sender<Request>, Doorbell),
    stats: &Arc<Mutex<Stats>>,
    (config, model): (&Config, &Option<Arc<IcaModel>>),
    tracker: &TaskTracker,
) -> ControlCtx {
    ControlCtx {
        socket: Arc::new(socket),
        cmd_tx,
        bell,
        stats: Arc::clone(stats),
        model_path: Arc::new(Mutex::new(config.model.clone())),
        model: Arc::new(Mutex::new(model.clone())),
        tracker: tracker.clone(),
        guard: Arc::new(Guard::new(config)),
    }
}

/// Wakes the processing thread when `shutdown` is cancelled, so it stops reading the frame
/// socket at once.
pub(super) fn ring_on_shutdown(
    bell: Doorbell,
    tracker: &TaskTracker,
    shutdown: &CancellationToken,
) {
    let shutdown = shutdown.clone();
    tracker.spawn(async move {
        shutdown.cancelled().await;
        bell.ring();
    });
}
