//! The session recording as a sink ([`Recorder`]): idle until `/record/start`, then every
//! processed frame to the running [`Recording`]; closed on `/record/stop`, a new start or
//! shutdown, each close on its own thread (every file ends with an fsync, which must not hold
//! up the frames).

use std::net::{SocketAddr, UdpSocket};
use std::path::Path;
use std::thread::JoinHandle;

use engine::{Needs, Processed, Sink};
use tokio::sync::oneshot;

use super::{RecordError, RecordFrame, Recording};
use crate::serve::command::{Refusal, Reply};

/// The recording running, if any, and the ones closing.
#[derive(Debug, Default)]
pub struct Recorder {
    running: Option<Recording>,
    closing: Vec<JoinHandle<()>>,
    /// Why the last recording stopped by itself (a full disk), until the next start.
    error: Option<String>,
    /// The control socket, to tell a controller its recording stopped (`None` in tests).
    news: Option<UdpSocket>,
}

impl Recorder {
    /// No recording.
    pub fn new() -> Recorder {
        Recorder::default()
    }

    /// Tells a recording's controller over `socket` (the control socket) when it stops by
    /// itself.
    pub fn telling(mut self, socket: UdpSocket) -> Recorder {
        self.news = Some(socket);
        self
    }

    /// Why the last recording stopped by itself (a full disk, a write error), naming the
    /// file, the frames it keeps and the cause, until the next `/record/start`.
    pub fn error(&self) -> Option<&str> {
        self.error.as_deref()
    }

    /// The running recording's files: the edited stream's first, and the raw input's.
    pub fn paths(&self) -> Option<(&Path, Option<&Path>)> {
        self.running.as_ref().map(Recording::paths)
    }

    /// Starts a recording: refused while one runs to the same path; one running to another
    /// path is closed once the new one is ready (a bad new path leaves it running).
    /// `controller`, the OSC peer asking, hears `/emoshift/error` if it stops by itself.
    pub(crate) fn start(
        &mut self,
        path: &Path,
        raw: Option<&Path>,
        overwrite: bool,
        controller: Option<SocketAddr>,
    ) -> Reply {
        let refused = |e: RecordError| Refusal::from_error(Refusal::Record, &e);
        if let Some(running) = &self.running {
            if running.writes_to(path) {
                let path = path.display().to_string();
                return Err(refused(RecordError::Running { path }));
            }
        }
        let rec = Recording::start(path, raw, overwrite)
            .map_err(refused)?
            .told_to(controller);
        self.error = None;
        if let Some(old) = self.running.replace(rec) {
            tracing::info!(target: "emoshift", to = %path.display(), "recording closed for a new one");
            self.closing.push(close_in_background(old, None));
        }
        Ok(())
    }

    /// Starts a recording as `/record/start PATH [RAW]` does, without a controller to tell
    /// (benches and tools that drive a [`Recorder`] directly).
    ///
    /// # Errors
    /// Why the recording cannot start (the path exists, its folder does not, an unknown
    /// extension), as `/record/start` would answer.
    pub fn start_at(&mut self, path: &Path, raw: Option<&Path>) -> Result<(), String> {
        self.start(path, raw, false, None)
            .map_err(|refusal| refusal.to_string())
    }

    /// Stops the recording; `reply` is answered once its files are complete.
    pub(crate) fn stop(&mut self, reply: oneshot::Sender<Reply>) {
        match self.running.take() {
            Some(rec) => self.closing.push(close_in_background(rec, Some(reply))),
            None => {
                let _ = reply.send(Err(Refusal::Record("no recording in progress".into())));
            }
        }
    }

    /// Forgets the closes that are done.
    pub fn tidy(&mut self) {
        self.closing.retain(|h| !h.is_finished());
    }

    /// Closes the recording and waits for every file to be complete (shutdown).
    pub fn finish(mut self) {
        if let Some(rec) = self.running.take() {
            if let Err(e) = rec.finish() {
                tracing::warn!(target: "emoshift", error = %e, "recording failed: check the path and the free space, then /record/start again");
            }
        }
        for closing in self.closing.drain(..) {
            let _ = closing.join();
        }
    }
}

impl Sink for Recorder {
    fn needs(&self) -> Needs {
        match self.running {
            Some(_) => Needs {
                markers: true,
                labels: true,
                input: true,
                time: true,
                ..Needs::NOTHING
            },
            None => Needs::NOTHING,
        }
    }

    fn handle_frame(&mut self, frame: &Processed<'_>) {
        if let Some(rec) = self.running.as_mut() {
            rec.push(&RecordFrame::of(frame));
            if rec.stopped().is_some() {
                self.stopped();
            }
        }
    }
}

impl Recorder {
    /// A recording that stopped by itself (a full disk, a write error): closed with the
    /// frames that fit, and the cause told in the log, to the controller that started it
    /// (`/emoshift/error`) and in `/status` (`recording` cleared, `recording_error` set). The
    /// stream goes on.
    fn stopped(&mut self) {
        let Some(rec) = self.running.take() else {
            return;
        };
        let why = format!(
            "recording stopped: {}; free space or /record/start to another disk",
            rec.stopped().unwrap_or("a write error")
        );
        tracing::error!(target: "emoshift", error = %why, "recording stopped; the stream goes on");
        if let (Some(socket), Some(to)) = (&self.news, rec.controller()) {
            let mut out = Vec::with_capacity(256);
            protocol::encode_error_into(protocol::address::RECORD_START, &why, &mut out);
            let _ = socket.send_to(&out, to);
        }
        self.error = Some(why);
        self.closing.push(close_in_background(rec, None));
    }
}

/// Closes a recording on its own thread, answering `reply` when done.
fn close_in_background(rec: Recording, reply: Option<oneshot::Sender<Reply>>) -> JoinHandle<()> {
    std::thread::spawn(move || {
        let r = rec
            .finish()
            .map(|_| ())
            .map_err(|e| Refusal::from_error(Refusal::Record, &e));
        if let Err(e) = &r {
            tracing::warn!(target: "emoshift", error = %e, "recording failed: check the path and the free space, then /record/start again");
        }
        if let Some(reply) = reply {
            let _ = reply.send(r);
        }
    })
}
