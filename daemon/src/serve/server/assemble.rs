//! What the processing thread runs, put together from the config: the engine over the models
//! (or without one: frames pass through) and every output.

use std::sync::Arc;

use anyhow::Result;
use engine::pipeline::{Pipeline, PipelineConfig};
use engine::Performer;
use ica_core::model::IcaModel;

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
