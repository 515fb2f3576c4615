//! The output port: every output is a [`Sink`]. The engine pushes each processed frame
//! ([`Processed`]) once to the sink it is given; a sink reads what it needs of it, owns its own
//! clients, leases and back-pressure, and never makes the frame path wait (a full socket drops
//! a datagram, a slow page loses a snapshot). The shell's sinks: the OSC output (its three
//! profiles), the session recording and the monitor page's feed; the shell hands the engine
//! one sink that passes each frame to all of them.
//!
//! Modelled on ripgrep's searcher `Sink`: the producer (here [`crate::Pipeline`]) knows
//! nothing of what a sink does with a frame, so a new output (a NatNet or QTM server) is a
//! new sink and no change to the frame path.

use protocol::{FrameBuf, FrameTime};

use crate::stream::{Identity, Stream};
use crate::streams::StreamKey;

/// What a sink reads of a processed frame. The engine resynthesises the edited markers only
/// when a sink reads them; the rest is always at hand and declared for the reader's sake (and
/// for the shell's status).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Needs {
    /// The edited markers ([`Processed::output`]).
    pub markers: bool,
    /// The components after (and before) the edit ([`Stream::components`]).
    pub components: bool,
    /// The emotion state: target, amount, bypass ([`Stream::edit`]).
    pub state: bool,
    /// The stream's labels ([`Processed::labels`]), and when they are due.
    pub labels: bool,
    /// The frame as received, in source order, with its labels ([`Processed::input`]).
    pub input: bool,
    /// The source's timecode and capture clock ([`Processed::time`]).
    pub time: bool,
}

impl Needs {
    /// Nothing: a sink with no client.
    pub const NOTHING: Needs = Needs {
        markers: false,
        components: false,
        state: false,
        labels: false,
        input: false,
        time: false,
    };

    /// What either `self` or `other` needs.
    pub fn or(self, other: Needs) -> Needs {
        Needs {
            markers: self.markers || other.markers,
            components: self.components || other.components,
            state: self.state || other.state,
            labels: self.labels || other.labels,
            input: self.input || other.input,
            time: self.time || other.time,
        }
    }
}

/// One processed frame, borrowed from the engine's buffers for the length of one
/// [`Sink::handle_frame`] call.
#[derive(Debug, Clone, Copy)]
pub struct Processed<'a> {
    /// The stream.
    pub key: StreamKey,
    /// The stream's state after this frame: identity, model, edit, components before and
    /// after the edit, the frame in model order with its gaps, order counters.
    pub stream: &'a Stream,
    /// The edited frame in model order (gaps filled by the model): frame number and capture
    /// time as received. Stale when no sink [`Needs::markers`].
    pub output: &'a FrameBuf,
    /// The frame as received: every marker the source sent, in its order, with its gaps.
    pub input: &'a FrameBuf,
    /// The source's time of the frame: SMPTE timecode and capture clock.
    pub time: &'a FrameTime,
    /// Frame numbers since the stream's previous processed frame: 1 when none was lost or
    /// dropped on the way (and for a stream's first frame or a restart).
    pub frames_since_last: u32,
    /// The stream's labels go to every client with this frame (the stream's first, then once a
    /// second); a client new to the stream needs them with its first frame regardless.
    pub labels_due: bool,
}

impl Processed<'_> {
    /// Who the stream is to clients.
    pub fn identity(&self) -> &Identity {
        &self.stream.identity
    }

    /// The frame number.
    pub fn frame_number(&self) -> i32 {
        self.output.header().frame_number
    }

    /// The stream's model labels, the order of [`Processed::output`] (the source's labels when
    /// the stream has no model and passes its frames through).
    pub fn labels(&self) -> &[String] {
        self.stream.labels()
    }

    /// The source's labels of [`Processed::input`].
    pub fn input_labels(&self) -> &[String] {
        self.stream.source_labels()
    }

    /// The stream's model rate (the pipeline's passthrough rate without a model).
    pub fn rate_hz(&self) -> f64 {
        self.stream.rate_hz()
    }

    /// The edited positions in model order (gaps filled by the model).
    pub fn xyz(&self) -> &[f32] {
        self.stream.edited()
    }
}

/// An output: it gets each processed frame once. See the module docs.
pub trait Sink {
    /// What it reads of a frame now (it may change as clients come and go).
    fn needs(&self) -> Needs;

    /// One processed frame. Must not block: what cannot be sent now is dropped and counted.
    fn handle_frame(&mut self, frame: &Processed<'_>);

    /// Streams that are gone (their source went quiet and the engine forgot them,
    /// [`crate::Pipeline::forget_quiet_streams`]): a sink that announces its streams to its
    /// clients (a NatNet or QTM server's model definitions) tells them. A stream that is made
    /// again, or relabelled, shows in its next frame (the same id, other labels or model).
    fn handle_gone(&mut self, _gone: &[StreamKey]) {}
}

/// Frames dropped on the floor: a pipeline with no output (tests, warm-up).
#[derive(Debug, Clone, Copy, Default)]
pub struct Discard;

impl Sink for Discard {
    fn needs(&self) -> Needs {
        Needs::NOTHING
    }

    fn handle_frame(&mut self, _frame: &Processed<'_>) {}
}

/// A closure as a sink that needs everything (tests, one-off readers).
#[derive(Debug)]
pub struct Each<F>(pub F);

impl<F: FnMut(&Processed<'_>)> Sink for Each<F> {
    fn needs(&self) -> Needs {
        Needs {
            markers: true,
            components: true,
            state: true,
            labels: true,
            input: true,
            time: true,
        }
    }

    fn handle_frame(&mut self, frame: &Processed<'_>) {
        (self.0)(frame);
    }
}
