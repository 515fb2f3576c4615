//! Control requests, applied by the processing thread between frames, so a command always takes
//! effect at a frame boundary and its reply says what the engine actually did.

use std::path::Path;

use super::Processing;
use crate::serve::command::{Command, Refusal, Reply, Request};
use crate::serve::record::{close_in_background, RecordError, Recording};

impl Processing {
    pub(super) fn command(&mut self, request: Request) {
        let Request { command, reply } = request;
        let answer: Option<Reply> = match command {
            Command::Edit(control) => Some(
                self.pipeline
                    .handle_edit(&control)
                    .map_err(|e| Refusal::Edit(e.to_string())),
            ),
            Command::Client { peer, control } => {
                let r = self.fanout.command(peer, &control);
                self.pipeline.set_wanted(self.fanout.wanted());
                Some(r.map_err(Refusal::Client))
            }
            Command::SetModel(model) => Some(
                self.pipeline
                    .check_model(&model)
                    .map(|()| self.pipeline.set_model(model))
                    .map_err(|e| Refusal::Model(e.to_string())),
            ),
            Command::RecordStart {
                path,
                raw,
                overwrite,
            } => Some(self.record_start(&path, raw.as_deref(), overwrite)),
            Command::RecordStop => match self.recording.take() {
                Some(rec) => {
                    // Answered by the closing thread once the files are complete.
                    self.closing.push(close_in_background(rec, Some(reply)));
                    return;
                }
                None => Some(Err(Refusal::Record("no recording in progress".into()))),
            },
        };
        if let Some(answer) = answer {
            let _ = reply.send(answer);
        }
    }

    /// Starts a recording: refused while one runs to the same path; one running to another
    /// path is closed once the new one is ready (a bad new path leaves it running).
    fn record_start(&mut self, path: &Path, raw: Option<&Path>, overwrite: bool) -> Reply {
        let refused = |e: RecordError| Refusal::from_error(Refusal::Record, &e);
        if let Some(running) = &self.recording {
            if running.writes_to(path) {
                let path = path.display().to_string();
                return Err(refused(RecordError::Running { path }));
            }
        }
        let rec = Recording::start(path, raw, overwrite).map_err(refused)?;
        if let Some(old) = self.recording.replace(rec) {
            tracing::info!(target: "emoshift", to = %path.display(), "recording closed for a new one");
            self.closing.push(close_in_background(old, None));
        }
        Ok(())
    }
}
