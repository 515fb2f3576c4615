//! Steps 4 to 7 of a frame's path once its source's labels are known, shared by every input
//! (OSC `/mocap/frame`, NatNet markersets): the stream found or made, [`Stream::process`],
//! the outputs encoded once, `emit`.
//!
//! Free functions over the pipeline's fields rather than methods: the caller holds the labels
//! borrowed from one field (the layout book) while these take others mutably.

use protocol::{FrameBuf, FrameHeader, FrameTime};

use super::encode::{Outputs, ProfileMask};
use super::setup::{new_stream, Defaults};
use super::Emitted;
use crate::engine::stream::Stream;
use crate::engine::streams::{StreamKey, Streams};
use crate::engine::Counters;

/// The stream of `key`, made on its first frame from `labels` (and `name`, a NatNet
/// markerset's); `None` (counted) when it cannot be made.
pub(super) fn stream_for<'s>(
    streams: &'s mut Streams,
    key: StreamKey,
    labels: &[String],
    name: Option<&str>,
    defaults: &Defaults<'_>,
    counters: &mut Counters,
) -> Option<&'s mut Stream> {
    let stream = streams.get_or_create(key, |id| new_stream(id, &key, labels, name, defaults));
    if stream.is_none() {
        counters.dropped_unmatched += 1;
    }
    stream
}

/// What steps 4 to 7 borrow from the pipeline, built by `step!` field by field (the caller
/// may hold the labels borrowed from another field).
pub(super) struct Step<'a> {
    pub(super) streams: &'a mut Streams,
    pub(super) defaults: Defaults<'a>,
    pub(super) io: Io<'a>,
}

/// Borrows a [`Step`] from the pipeline `$p`'s fields.
macro_rules! step {
    ($p:expr) => {
        $crate::engine::pipeline::run::Step {
            streams: &mut $p.streams,
            defaults: $crate::engine::pipeline::setup::Defaults {
                performers: &$p.performers,
                model: &$p.model,
                template: &$p.template,
                lowpass_s: $p.config.lowpass_s,
            },
            io: $crate::engine::pipeline::run::Io {
                frame_in: &$p.frame_in,
                frame_out: &mut $p.frame_out,
                outputs: &mut $p.outputs,
                wanted: $p.wanted,
                time: &$p.time_in,
                counters: &mut $p.counters,
            },
        }
    };
}
pub(super) use step;

/// Steps 4 to 7 of a frame whose source's labels are known: its stream (made on its first
/// frame), then [`run_stream`].
pub(super) fn frame_step(
    s: Step<'_>,
    key: StreamKey,
    (labels, name): (&[String], Option<&str>),
    header: &FrameHeader,
    emit: &mut dyn FnMut(&Emitted<'_>),
) {
    let Step {
        streams,
        defaults,
        io,
    } = s;
    if let Some(stream) = stream_for(streams, key, labels, name, &defaults, io.counters) {
        run_stream(stream, key, header, io, emit);
    }
}

/// The buffers a frame goes through, borrowed from the pipeline.
pub(super) struct Io<'a> {
    /// The frame as received, in source order.
    pub(super) frame_in: &'a FrameBuf,
    /// The edited frame.
    pub(super) frame_out: &'a mut FrameBuf,
    /// The encoded outputs.
    pub(super) outputs: &'a mut Outputs,
    /// Profiles to encode.
    pub(super) wanted: ProfileMask,
    /// The source's time of the frame.
    pub(super) time: &'a FrameTime,
    /// Counters.
    pub(super) counters: &'a mut Counters,
}

/// [`Stream::process`], encode, emit.
pub(super) fn run_stream(
    stream: &mut Stream,
    key: StreamKey,
    header: &FrameHeader,
    io: Io<'_>,
    emit: &mut dyn FnMut(&Emitted<'_>),
) {
    let Io {
        frame_in,
        frame_out,
        outputs,
        wanted,
        time,
        counters,
    } = io;
    let Some(done) = stream.process(header, frame_in, frame_out, counters) else {
        return;
    };
    let (tag, edit) = (stream.identity.tag(), &stream.edit);
    let (u, vmc) = (stream.components(), &stream.vmc);
    if outputs
        .encode(wanted, &tag, frame_out, edit, (u, vmc), time)
        .is_err()
    {
        counters.frame_errors += 1;
        return;
    }
    counters.frames_out += 1;
    let out = &*outputs;
    emit(&Emitted {
        key,
        identity: &stream.identity,
        labels_msg: stream.labels_msg(),
        labels_due: done.labels_due,
        frame_number: header.frame_number,
        frames_since_last: done.frames_since_last,
        compact: &out.compact,
        parts: &out.parts,
        part_ends: &out.part_ends,
        components: &out.components,
        xyz: stream.edited(),
        input: frame_in,
        input_labels: stream.source_labels(),
        labels: stream.model.labels(),
        rate_hz: stream.model.rate_hz(),
        time,
    });
}
