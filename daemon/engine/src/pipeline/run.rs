//! Steps 2 to 4 of a frame's path (see [`crate`]): the stream found or made, [`Stream::process`],
//! the processed frame to the sink.

use protocol::{FrameBuf, FrameTime};

use super::setup::{new_stream, Defaults};
use crate::input::SourceFrame;
use crate::output::{Processed, Sink};
use crate::stream::Stream;
use crate::streams::Streams;
use crate::Counters;

/// The buffers a frame goes through, borrowed from the pipeline.
pub(super) struct Io<'a> {
    /// The edited frame.
    pub(super) frame_out: &'a mut FrameBuf,
    /// The source's time of the frame.
    pub(super) time: &'a FrameTime,
    /// The pipeline's sweep count (the stream was heard in it).
    pub(super) sweep: u64,
    /// Counters.
    pub(super) counters: &'a mut Counters,
}

/// The stream of `frame` (made on its first frame; `None`, counted, when it cannot be made),
/// then [`run_stream`].
pub(super) fn frame_step(
    streams: &mut Streams,
    defaults: &Defaults<'_>,
    frame: &SourceFrame<'_>,
    io: Io<'_>,
    sink: &mut dyn Sink,
) {
    let key = frame.key;
    let performer = frame.performer.map(|p| &**p);
    let stream = streams.get_or_create(key, |id| {
        new_stream(id, &key, frame.labels, performer, defaults)
    });
    match stream {
        Some(stream) => run_stream(stream, frame, io, sink),
        None => io.counters.dropped_unmatched += 1,
    }
}

/// [`Stream::process`], then the processed frame to `sink` once.
fn run_stream(stream: &mut Stream, frame: &SourceFrame<'_>, io: Io<'_>, sink: &mut dyn Sink) {
    let Io {
        frame_out,
        time,
        sweep,
        counters,
    } = io;
    stream.heard_sweep = sweep;
    let header = frame.frame.header();
    // Resynthesis only when a sink reads the markers (a components-only output does not).
    let output = sink.needs().markers.then_some(&mut *frame_out);
    let Some(done) = stream.process(&header, frame.frame, output, counters) else {
        return;
    };
    counters.frames_out += 1;
    sink.handle_frame(&Processed {
        key: frame.key,
        stream,
        output: frame_out,
        input: frame.frame,
        time,
        frames_since_last: done.frames_since_last,
        labels_due: done.labels_due,
    });
}
