//! Control requests, applied by the processing thread between frames, so a command always takes
//! effect at a frame boundary and its reply says what the engine actually did.

use super::Processing;
use crate::serve::command::{Command, Refusal, Reply, Request};

impl Processing {
    pub(super) fn command(&mut self, request: Request) {
        let Request { command, reply } = request;
        let answer: Reply = match command {
            Command::Edit(control) => self
                .pipeline
                .handle_edit(&control)
                .map_err(|e| Refusal::Edit(e.to_string())),
            Command::Client { peer, control } => self
                .outputs
                .osc
                .handle_control(peer, &control)
                .map_err(Refusal::Client),
            Command::SetModel(model) => self
                .pipeline
                .check_model(&model)
                .map(|()| self.pipeline.set_model(model))
                .map_err(|e| Refusal::Model(e.to_string())),
            Command::RecordStart {
                path,
                raw,
                overwrite,
                controller,
            } => self
                .outputs
                .recorder
                .start(&path, raw.as_deref(), overwrite, controller),
            // Answered by the closing thread once the files are complete (after an fsync each,
            // so the merge below comes first).
            Command::RecordStop => {
                self.outputs.recorder.stop(reply);
                return self.merge_stats();
            }
        };
        // So that a `/status` sent on the reply sees the command's effect.
        self.merge_stats();
        let _ = reply.send(answer);
    }
}
