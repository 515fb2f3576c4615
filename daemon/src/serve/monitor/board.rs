//! Where the processing thread leaves each stream's latest snapshot for the pages, and the
//! processing thread's side of it ([`Feed`]). Latest wins: a snapshot replaces the stream's
//! previous one, whether or not a page took it.

use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use tokio::sync::Notify;

use engine::monitor::{MonitorTap, Snapshot, DEFAULT_MONITOR_HZ};
use engine::pipeline::MAX_SOURCES;
use engine::{Needs, Processed, Sink};

/// The latest snapshot of each stream, and who is watching.
#[derive(Debug, Default)]
pub struct Board {
    slots: Mutex<Vec<Snapshot>>,
    notify: Notify,
    viewers: AtomicUsize,
    unpublished: AtomicU64,
}

impl Board {
    /// An empty board, nobody watching.
    pub fn new() -> Board {
        Board::default()
    }

    /// Whether a page is open (the processing thread copies nothing otherwise).
    pub fn watched(&self) -> bool {
        self.viewers.load(Ordering::Relaxed) > 0
    }

    /// Sets how many pages are open.
    pub fn set_viewers(&self, n: usize) {
        self.viewers.store(n, Ordering::Relaxed);
    }

    /// Snapshots not published because the pages' side held the board.
    pub fn unpublished(&self) -> u64 {
        self.unpublished.load(Ordering::Relaxed)
    }

    /// Publishes `snap` as its stream's latest, never waiting: the board's previous snapshot
    /// of that stream comes back in `snap`, buffers and all, so nothing is allocated once
    /// every stream has a slot. `false` (counted) when the board was busy.
    pub fn publish(&self, snap: &mut Snapshot) -> bool {
        let Ok(mut slots) = self.slots.try_lock() else {
            self.unpublished.fetch_add(1, Ordering::Relaxed);
            return false;
        };
        let at = slots.iter().position(|s| s.stream_id == snap.stream_id);
        match at {
            Some(i) => std::mem::swap(&mut slots[i], snap),
            None if slots.len() < MAX_SOURCES => slots.push(std::mem::take(snap)),
            // Past the cap the slot of the stream quietest for longest goes.
            None => {
                if let Some(oldest) = slots.iter_mut().min_by_key(|s| s.at_us) {
                    std::mem::swap(oldest, snap);
                }
            }
        }
        drop(slots);
        self.notify.notify_one();
        true
    }

    /// Waits until something is published.
    pub(crate) async fn published(&self) {
        self.notify.notified().await;
    }

    /// Calls `each` with every snapshot newer than `seen` (the highest `seq` handed out
    /// before), and returns the new highest. Holds the board meanwhile: keep `each` short.
    pub(crate) fn fresh(&self, seen: u64, mut each: impl FnMut(&Snapshot)) -> u64 {
        let Ok(slots) = self.slots.lock() else {
            return seen;
        };
        let mut top = seen;
        for s in slots.iter().filter(|s| s.seq > seen) {
            top = top.max(s.seq);
            each(s);
        }
        top
    }

    /// Drops the slots of streams no longer running.
    pub(crate) fn retain(&self, alive: impl Fn(i32) -> bool) {
        if let Ok(mut slots) = self.slots.lock() {
            slots.retain(|s| alive(s.stream_id));
        }
    }
}

/// The processing thread's side: the engine's tap and the board.
#[derive(Debug)]
pub struct Feed {
    tap: MonitorTap,
    board: Arc<Board>,
    epoch: Instant,
}

impl Feed {
    /// A feed onto `board` at the default 30 Hz per stream.
    pub fn new(board: Arc<Board>) -> Feed {
        Feed {
            tap: MonitorTap::new(DEFAULT_MONITOR_HZ),
            board,
            epoch: Instant::now(),
        }
    }
}

impl Sink for Feed {
    /// Everything the page draws while a page is open; nothing otherwise.
    fn needs(&self) -> Needs {
        match self.board.watched() {
            true => Needs {
                markers: true,
                components: true,
                state: true,
                ..Needs::NOTHING
            },
            false => Needs::NOTHING,
        }
    }

    /// Nothing but an atomic load while no page is open; otherwise the frame is copied when
    /// its stream is due.
    fn handle_frame(&mut self, frame: &Processed<'_>) {
        if !self.board.watched() {
            return;
        }
        let now_us = self.epoch.elapsed().as_micros() as u64;
        if let Some(snap) = self.tap.handle_stream(now_us, frame.stream) {
            self.board.publish(snap);
        }
    }
}
