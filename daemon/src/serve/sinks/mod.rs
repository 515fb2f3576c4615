//! The outputs, one folder per kind, each an [`engine::Sink`]: it declares what it reads of a
//! processed frame, gets each frame once, owns its clients and never makes the frame path
//! wait.
//!
//! - [`osc`]: the OSC profiles (compact, flat-split, components) to `--send` targets and
//!   `/subscribe`rs;
//! - [`recording`]: the session recording (`/record/start`), edited and raw;
//! - [`natnet`]: the NatNet server (`--natnet-server`): Motive's look to NatNet clients;
//! - the monitor page's feed ([`crate::serve::monitor::Feed`]), beside the page it feeds.
//!
//! [`Outputs`] is the one sink the processing thread hands the engine: it passes each frame to
//! the OSC output first (the subscribers' path), then to the others. A new output (a NatNet or
//! QTM server) is a folder here, its config keys, and one line where `serve` builds
//! [`Outputs`]: a sink with its own sockets and per-client protocol versions keeps them to
//! itself ([`engine::subscribers`] is the bookkeeping sinks with clients share).

pub mod natnet;
pub mod osc;
pub mod qtm;
pub mod recording;

use engine::{Needs, Processed, Sink, StreamKey};

use self::osc::OscOutput;
use self::recording::Recorder;

/// Every output of the service.
pub struct Outputs {
    /// The OSC output (controls reach it: `/subscribe`, `/unsubscribe`).
    pub osc: OscOutput,
    /// The session recording (controls reach it: `/record/start`, `/record/stop`).
    pub recorder: Recorder,
    /// The other sinks, each after the two above (the monitor feed when the page is served).
    pub others: Vec<Box<dyn Sink + Send>>,
}

impl std::fmt::Debug for Outputs {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Outputs")
            .field("osc", &self.osc)
            .field("recorder", &self.recorder)
            .field("others", &self.others.len())
            .finish()
    }
}

impl Sink for Outputs {
    fn needs(&self) -> Needs {
        let first = self.osc.needs().or(self.recorder.needs());
        self.others.iter().fold(first, |n, s| n.or(s.needs()))
    }

    fn handle_frame(&mut self, frame: &Processed<'_>) {
        // The subscribers first: the file write and the page's copy are never on their path.
        self.osc.handle_frame(frame);
        self.recorder.handle_frame(frame);
        for sink in &mut self.others {
            sink.handle_frame(frame);
        }
    }

    fn handle_gone(&mut self, gone: &[StreamKey]) {
        self.osc.handle_gone(gone);
        self.recorder.handle_gone(gone);
        for sink in &mut self.others {
            sink.handle_gone(gone);
        }
    }
}
