//! The file's own thread: writes what the caller appended, syncs, then updates the header
//! (see the parent module for the cadence and what a crash can lose).

use std::fs::File;
use std::io::{Seek, SeekFrom, Write};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use super::{Header, Shared, State, Stopped, FLUSH, SYNC, WAKE_BYTES};

/// The file's thread.
pub(super) struct Disk {
    pub(super) file: File,
    pub(super) path: PathBuf,
    pub(super) header: Box<dyn Header>,
    pub(super) shared: Arc<Shared>,
    /// The buffer swapped with the caller's pending bytes.
    pub(super) spare: Vec<u8>,
    /// Whole frames written.
    pub(super) frames: u64,
    /// Frames the header counts.
    pub(super) counted: u64,
    /// The new file's directory entry was synced.
    pub(super) synced_dir: bool,
    pub(super) camera_rate_hz: Option<f64>,
}

impl Disk {
    pub(super) fn run(&mut self) -> Result<u64, Stopped> {
        let mut next_sync = Instant::now() + SYNC;
        // The header was updated but that update is not yet synced.
        let mut header_dirty = false;
        loop {
            let (frames, closing, stopped) = self.take_pending(next_sync);
            if stopped {
                return self.stop(None);
            }
            if !self.spare.is_empty() {
                if let Err(e) = self.write_spare(frames) {
                    return self.stop(Some(e));
                }
            }
            if closing {
                return self.close();
            }
            if Instant::now() < next_sync {
                continue;
            }
            if self.frames > self.counted || header_dirty {
                let news = self.frames > self.counted;
                if let Err(e) = self.sync_and_count() {
                    return self.stop(Some(e));
                }
                // A new count is durable only after the next sync.
                header_dirty = news;
            }
            next_sync = Instant::now() + SYNC;
        }
    }

    /// Waits for news (at most [`FLUSH`], and not past `next_sync`), then swaps the pending bytes into `spare`: their
    /// frame count, whether the caller is closing, whether the file was stopped.
    fn take_pending(&mut self, next_sync: Instant) -> (u64, bool, bool) {
        let shared = Arc::clone(&self.shared);
        let mut s = shared.lock();
        let quiet = |s: &State| !s.closing && s.stopped.is_none() && s.pending.len() < WAKE_BYTES;
        let wait = FLUSH.min(next_sync.saturating_duration_since(Instant::now()));
        if quiet(&s) {
            s = shared
                .wake
                .wait_timeout_while(s, wait, |s| quiet(s))
                .map(|(s, _)| s)
                .unwrap_or_else(|e| e.into_inner().0);
        }
        self.spare.clear();
        std::mem::swap(&mut self.spare, &mut s.pending);
        let frames = std::mem::take(&mut s.pending_frames);
        self.camera_rate_hz = s.camera_rate_hz.or(self.camera_rate_hz);
        // Room again for a caller waiting on it.
        shared.wake.notify_all();
        (frames, s.closing, s.stopped.is_some())
    }

    /// Writes `spare` (`frames` whole frames); on an error, keeps the whole frames that got
    /// through and cuts off the rest.
    fn write_spare(&mut self, frames: u64) -> std::io::Result<()> {
        let mut written = 0;
        while written < self.spare.len() {
            match self.file.write(&self.spare[written..]) {
                Ok(0) => {
                    return self.cut(written, std::io::ErrorKind::WriteZero.into());
                }
                Ok(n) => written += n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return self.cut(written, e),
            }
        }
        self.frames += frames;
        Ok(())
    }

    /// After a write error `e` with `written` bytes of `spare` through: counts the whole
    /// frames among them, cuts the file after them and returns `e`.
    fn cut(&mut self, written: usize, e: std::io::Error) -> std::io::Result<()> {
        let (frames, len) = self.header.whole(&self.spare[..written]);
        self.frames += frames;
        let cut = self.file.stream_position().and_then(|at| {
            let end = at - (written - len) as u64;
            self.file.set_len(end)?;
            self.file.seek(SeekFrom::Start(end))
        });
        // The cause is `e`; a failed cut only leaves a torn frame past the header's count.
        drop(cut);
        Err(e)
    }

    /// Makes the data durable, then the header count it.
    fn sync_and_count(&mut self) -> std::io::Result<()> {
        self.file.sync_data()?;
        if !self.synced_dir {
            // A new file's name survives a power cut only once its directory is synced.
            if let Some(dir) = self.path.parent().filter(|d| !d.as_os_str().is_empty()) {
                File::open(dir).and_then(|d| d.sync_all())?;
            }
            self.synced_dir = true;
        }
        if self.frames > 0 {
            let end = self.file.stream_position()?;
            self.header
                .count(&mut self.file, self.frames, self.camera_rate_hz)?;
            self.file.seek(SeekFrom::Start(end))?;
            self.counted = self.frames;
        }
        Ok(())
    }

    /// Closes the file complete: the final count, the format's end, a sync.
    fn close(&mut self) -> Result<u64, Stopped> {
        self.finish_file().map_err(|cause| Stopped {
            frames: self.counted,
            cause,
        })?;
        Ok(self.frames)
    }

    fn finish_file(&mut self) -> std::io::Result<()> {
        let end = self.file.stream_position()?;
        if self.frames > 0 {
            self.header
                .count(&mut self.file, self.frames, self.camera_rate_hz)?;
            self.counted = self.frames;
        }
        self.file.seek(SeekFrom::Start(end))?;
        self.header.close(&mut self.file, &self.path, self.frames)?;
        self.file.sync_all()
    }

    /// Stops the file after `error` (or after the caller stopped it): the frames written
    /// whole are counted and synced, and the caller hears why from now on.
    fn stop(&mut self, error: Option<std::io::Error>) -> Result<u64, Stopped> {
        // Best effort: the header must count what got through even if the disk is full
        // (the header's bytes are already allocated, so rewriting them needs no room).
        let closed = self.finish_file();
        let mut s = self.shared.lock();
        let cause = match (error, s.stopped.take()) {
            (Some(e), _) => e,
            (None, Some(earlier)) => earlier.cause,
            (None, None) => std::io::Error::other("stopped"),
        };
        let cause = match closed {
            Ok(()) => cause,
            Err(close) => std::io::Error::new(
                cause.kind(),
                format!("{cause}; the header could not be updated either: {close}"),
            ),
        };
        let stopped = Stopped {
            frames: self.counted,
            cause,
        };
        s.stopped = Some(stopped.copy());
        s.pending.clear();
        s.pending_frames = 0;
        self.shared.wake.notify_all();
        Err(stopped)
    }
}
