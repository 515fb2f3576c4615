//! A take file written on its own thread and kept readable through a crash: the disk side of
//! the recorder.
//!
//! The caller appends each frame's bytes to a shared buffer (a lock held for one copy) and never
//! waits on the disk: no `write`, no `fsync`, no header update on its thread. The file's
//! thread, every [`FLUSH`], takes what was appended and writes it; every [`SYNC`] while there
//! is news, it writes what was appended, makes the data durable (`fdatasync`) and then updates
//! the header's count ([`Header::count`]) to the frames just synced, which the next sync makes
//! durable in turn. So the header never counts a frame that is not on disk, and with a disk
//! that syncs within a tenth of a second:
//! - after SIGKILL (the page cache survives) a reader sees every frame but those of the last
//!   [`SYNC`] and one sync (0.5 s);
//! - after a power cut, every frame but those of the last two [`SYNC`]s and their syncs (1 s).
//!
//! Frames past the header's count are whole frames a crash left uncounted: `emoshift repair`
//! counts them ([`crate::repair`]).
//!
//! **Write errors** (a full disk): the frames written whole are kept, a frame cut by the error
//! is cut off, the header counts the rest and the file is synced: a valid take of the frames
//! that fit. Later appends are refused with the cause ([`Stopped`]). A disk that falls more
//! than [`MAX_PENDING`] behind stops the file the same way (or makes the caller wait, for an
//! offline writer: [`Behind`]), so memory stays bounded.

mod counts;
mod disk;

use std::fs::File;
use std::path::Path;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;

use disk::Disk;
use std::time::Duration;

pub(crate) use counts::{C3dCount, CsvRows, TrcCount, COUNT_WIDTH, RATE_WIDTH};

/// Appended bytes are written at least this often.
pub const FLUSH: Duration = Duration::from_millis(200);
/// Written data is synced, and the header updated to count it, at least this often.
pub const SYNC: Duration = Duration::from_millis(400);
/// Bytes waiting to be written past which the file stops (or the caller waits): 30 s of a
/// 109-marker C3D face at 120 Hz.
pub const MAX_PENDING: usize = 64 << 20;
/// Bytes waiting that wake the file's thread before [`FLUSH`] ends: big writes, few of them.
const WAKE_BYTES: usize = 256 << 10;

/// What the file's format does with its header as frames are written.
pub(crate) trait Header: Send + 'static {
    /// Makes the header count `frames` frames (the data holds at least that many, synced),
    /// with the measured rate where the format stores one; the file's position is restored
    /// by the caller.
    ///
    /// # Errors
    /// An I/O error.
    fn count(
        &mut self,
        file: &mut File,
        frames: u64,
        camera_rate_hz: Option<f64>,
    ) -> std::io::Result<()>;

    /// Whole frames at the start of `bytes` (appended frames, of which a write error let
    /// only these through): how many, and their length.
    fn whole(&self, bytes: &[u8]) -> (u64, usize);

    /// What to do after the last frame (`frames` in all), before the final count: C3D pads
    /// its data to a whole block, or removes a file of no frames (it cannot hold one).
    ///
    /// # Errors
    /// An I/O error.
    fn close(&mut self, file: &mut File, path: &Path, frames: u64) -> std::io::Result<()>;
}

/// When the disk falls `MAX_PENDING` (64 MiB) behind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Behind {
    /// Stop the file (its frames so far kept) and refuse later frames: a live recording,
    /// whose caller must never wait.
    Stop,
    /// Make the caller wait: an offline writer, whose frames can wait for the disk.
    Wait,
}

/// Why a file stopped before it was finished: the cause, and the frames it keeps.
#[derive(Debug)]
pub struct Stopped {
    /// Frames the file holds, its header counting them.
    pub frames: u64,
    /// What stopped it.
    pub cause: std::io::Error,
}

impl Stopped {
    fn copy(&self) -> Stopped {
        Stopped {
            frames: self.frames,
            cause: copy_io(&self.cause),
        }
    }
}

/// An I/O error with the same kind and message (OS errors keep their code).
pub(crate) fn copy_io(e: &std::io::Error) -> std::io::Error {
    match e.raw_os_error() {
        Some(code) => std::io::Error::from_raw_os_error(code),
        None => std::io::Error::new(e.kind(), e.to_string()),
    }
}

/// What the caller and the file's thread share.
#[derive(Debug, Default)]
struct State {
    /// Whole frames' bytes appended and not yet taken by the file's thread.
    pending: Vec<u8>,
    /// Frames in `pending`.
    pending_frames: u64,
    /// The caller is done: write the rest and close.
    closing: bool,
    /// Set once the file stopped: later appends are refused with it.
    stopped: Option<Stopped>,
    /// The measured rate to store on the next count.
    camera_rate_hz: Option<f64>,
}

#[derive(Debug, Default)]
struct Shared {
    state: Mutex<State>,
    /// Wakes the file's thread (closing, much pending) and a caller waiting for room.
    wake: Condvar,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, State> {
        // A panic on the other side leaves the state consistent: every update is one field.
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// The caller's side of a file being written on its own thread. Dropping it without
/// [`DurableFile::finish`] still closes the file complete (and waits for it).
#[derive(Debug)]
pub(crate) struct DurableFile {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<Result<u64, Stopped>>>,
    /// What [`DurableFile::append`] does when the disk is far behind.
    pub(crate) behind: Behind,
}

impl DurableFile {
    /// Starts the file's thread on `file`, whose header (`head_len` bytes) is written and whose
    /// position is at its end.
    ///
    /// # Errors
    /// The thread cannot be spawned.
    pub(crate) fn start(
        file: File,
        path: &Path,
        header: Box<dyn Header>,
        behind: Behind,
    ) -> std::io::Result<DurableFile> {
        let shared = Arc::new(Shared::default());
        let mut disk = Disk {
            file,
            path: path.to_path_buf(),
            header,
            shared: Arc::clone(&shared),
            spare: Vec::new(),
            frames: 0,
            counted: 0,
            synced_dir: false,
            camera_rate_hz: None,
        };
        let thread = std::thread::Builder::new()
            .name("take-file".into())
            .spawn(move || disk.run())?;
        Ok(DurableFile {
            shared,
            thread: Some(thread),
            behind,
        })
    }

    /// Appends one whole frame's bytes. Never touches the disk; waits only with
    /// [`Behind::Wait`] while the disk is [`MAX_PENDING`] behind.
    ///
    /// # Errors
    /// [`Stopped`] once the file stopped (a write error, the disk too far behind).
    pub(crate) fn append(&self, frame: &[u8]) -> Result<(), Stopped> {
        let mut s = self.shared.lock();
        if let Some(stopped) = &s.stopped {
            return Err(stopped.copy());
        }
        if s.pending.len() + frame.len() > MAX_PENDING {
            match self.behind {
                Behind::Wait => {
                    while s.pending.len() + frame.len() > MAX_PENDING && s.stopped.is_none() {
                        self.shared.wake.notify_all();
                        s = self.shared.wake.wait(s).unwrap_or_else(|e| e.into_inner());
                    }
                    if let Some(stopped) = &s.stopped {
                        return Err(stopped.copy());
                    }
                }
                Behind::Stop => {
                    let waiting = s.pending.len() >> 20;
                    let cause = std::io::Error::other(format!(
                        "the disk did not keep up: {waiting} MiB were waiting to be written"
                    ));
                    // The file's thread writes no more and closes with what it wrote.
                    s.pending.clear();
                    s.pending_frames = 0;
                    s.stopped = Some(Stopped { frames: 0, cause });
                    self.shared.wake.notify_all();
                    return Err(s.stopped.as_ref().map(Stopped::copy).expect("set above"));
                }
            }
        }
        s.pending.extend_from_slice(frame);
        s.pending_frames += 1;
        if s.pending.len() >= WAKE_BYTES && s.pending.len() - frame.len() < WAKE_BYTES {
            self.shared.wake.notify_all();
        }
        Ok(())
    }

    /// The measured rate to store in the header from the next count on.
    pub(crate) fn set_camera_rate(&self, rate_hz: f64) {
        self.shared.lock().camera_rate_hz = Some(rate_hz);
    }

    /// Writes what is appended, closes the file complete and synced; the frames it holds.
    ///
    /// # Errors
    /// [`Stopped`] when the file stopped before (it is closed valid with the frames kept) or
    /// the close fails.
    pub(crate) fn finish(mut self) -> Result<u64, Stopped> {
        self.close()
    }

    fn close(&mut self) -> Result<u64, Stopped> {
        {
            let mut s = self.shared.lock();
            s.closing = true;
            self.shared.wake.notify_all();
        }
        match self.thread.take().map(JoinHandle::join) {
            Some(Ok(result)) => result,
            Some(Err(_)) => Err(Stopped {
                frames: 0,
                cause: std::io::Error::other("the take file's thread panicked"),
            }),
            None => Err(Stopped {
                frames: 0,
                cause: std::io::Error::other("the take file was already closed"),
            }),
        }
    }
}

impl Drop for DurableFile {
    fn drop(&mut self) {
        if self.thread.is_some() {
            // Nobody can hear an error here: the file is closed as well as it can be.
            let _ = self.close();
        }
    }
}

#[cfg(test)]
mod tests;
