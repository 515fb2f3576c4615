//! The processing queue: the frames of every source but the OSC frame socket (which the
//! processing thread reads itself), copied into pooled buffers, on one bounded channel to the
//! processing thread, whose [`Doorbell`] each push rings. When it is full the oldest frame is dropped and counted:
//! latest frame wins. Buffers go back to the pool once processed, so a warm queue allocates
//! nothing (labels and names are shared, not copied).

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use crossbeam_channel::{Receiver, Sender, TrySendError};
use engine::{SourceFrame, StreamKey};
use protocol::{FrameBuf, FrameTime};

use crate::serve::sources::Arrival;
use crate::serve::wake::Doorbell;

/// One source frame, owned, on its way to the processing thread.
#[derive(Debug)]
pub struct QueuedFrame {
    key: StreamKey,
    performer: Option<Arc<str>>,
    labels: Arc<[String]>,
    frame: FrameBuf,
    time: FrameTime,
    /// How it arrived.
    pub arrival: Arrival,
}

impl QueuedFrame {
    /// The frame as the engine reads it.
    pub fn source(&self) -> SourceFrame<'_> {
        SourceFrame {
            key: self.key,
            performer: self.performer.as_ref(),
            labels: &self.labels,
            frame: &self.frame,
            time: self.time,
        }
    }

    /// Its buffer, back to the pool.
    pub fn into_buffer(self) -> FrameBuf {
        self.frame
    }
}

/// The queue's ends as the sources' side uses them (cloned for each source task).
#[derive(Debug, Clone)]
pub struct Queue {
    tx: Sender<QueuedFrame>,
    /// To drop the oldest frame when full.
    rx: Receiver<QueuedFrame>,
    /// Buffers handed back by the processing thread.
    free: Receiver<FrameBuf>,
    /// Frames dropped because the queue was full.
    dropped: Arc<AtomicU64>,
    max_markers: usize,
    /// Wakes the processing thread.
    bell: Doorbell,
}

/// The processing thread's ends.
#[derive(Debug)]
pub struct QueueEnds {
    /// Queued frames.
    pub frames: Receiver<QueuedFrame>,
    /// Where processed frames' buffers go back.
    pub free: Sender<FrameBuf>,
}

/// Buffers kept in the pool.
const POOL: usize = 256;

impl Queue {
    /// A queue of `len` frames of up to `max_markers` markers, counting drops in `dropped`,
    /// ringing `bell` after each push.
    pub fn new(
        len: usize,
        max_markers: usize,
        dropped: Arc<AtomicU64>,
        bell: Doorbell,
    ) -> (Queue, QueueEnds) {
        let (tx, rx) = crossbeam_channel::bounded(len);
        let (free_tx, free) = crossbeam_channel::bounded(POOL);
        let queue = Queue {
            tx,
            rx: rx.clone(),
            free,
            dropped,
            max_markers,
            bell,
        };
        let ends = QueueEnds {
            frames: rx,
            free: free_tx,
        };
        (queue, ends)
    }

    /// Copies `frame` into a pooled buffer and queues it, dropping (and counting) the oldest
    /// frame when full. `false` once the processing thread is gone.
    pub fn push(&self, frame: &SourceFrame<'_>, arrival: &Arrival) -> bool {
        let mut buf = self
            .free
            .try_recv()
            .unwrap_or_else(|_| FrameBuf::with_max_markers(self.max_markers));
        let h = frame.frame.header();
        // A decoded frame's missing markers are NaN triples: the copy keeps them missing.
        if buf
            .set_frame(h.frame_number, h.capture_time_us, frame.frame.positions())
            .is_err()
        {
            return true;
        }
        let mut item = QueuedFrame {
            key: frame.key,
            performer: frame.performer.cloned(),
            labels: Arc::clone(frame.labels),
            frame: buf,
            time: frame.time,
            arrival: arrival.clone(),
        };
        loop {
            match self.tx.try_send(item) {
                Ok(()) => {
                    self.bell.ring();
                    return true;
                }
                Err(TrySendError::Full(back)) => {
                    item = back;
                    if self.rx.try_recv().is_ok() {
                        self.dropped.fetch_add(1, Ordering::Relaxed);
                    }
                }
                Err(TrySendError::Disconnected(_)) => return false,
            }
        }
    }
}
