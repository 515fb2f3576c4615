//! `/record/start <path>`: the edited stream (and optionally the raw input) written to C3D,
//! TRC or CSV by extension, closed complete on `/record/stop` or shutdown.

use std::path::{Path, PathBuf};

use replay::record::Recorder;

/// Why a recording could not start or finish.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// Not `.c3d`, `.trc` or `.csv`.
    #[error("{path}: record to a .c3d, .trc or .csv file")]
    Extension {
        /// The path.
        path: String,
    },
    /// The file cannot be created or written.
    #[error("{path}: {source}")]
    Io {
        /// The path.
        path: String,
        /// Why.
        source: std::io::Error,
    },
    /// The writer refused the take.
    #[error("{path}: {message}")]
    Write {
        /// The path.
        path: String,
        /// Why.
        message: String,
    },
}

/// One recording in progress, written frame by frame by [`Recorder`] (bounded memory, the
/// file is complete after [`Recording::finish`]). Frames arrive in model order with the
/// model's labels; the recorder opens on the first frame, which fixes labels, rate and the
/// first frame number.
#[derive(Debug)]
pub struct Recording {
    path: PathBuf,
    recorder: Option<Recorder>,
    missing: Vec<bool>,
    frames: usize,
    failed: bool,
}

impl Recording {
    /// Checks the extension and that the file can be created (so `/record/start` answers with
    /// the error at once, not at the end).
    ///
    /// # Errors
    /// [`RecordError::Extension`] or [`RecordError::Io`].
    pub fn start(path: &Path) -> Result<Recording, RecordError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        if !matches!(ext.as_deref(), Some("c3d" | "trc" | "csv")) {
            return Err(RecordError::Extension {
                path: path.display().to_string(),
            });
        }
        std::fs::File::create(path).map_err(|source| RecordError::Io {
            path: path.display().to_string(),
            source,
        })?;
        Ok(Recording {
            path: path.to_path_buf(),
            recorder: None,
            missing: Vec::new(),
            frames: 0,
            failed: false,
        })
    }

    /// Appends one edited frame. A write error stops the recording (logged once); the frames
    /// written so far stay in the file.
    pub fn push(&mut self, labels: &[String], rate_hz: f64, frame_number: i32, xyz: &[f32]) {
        if self.failed {
            return;
        }
        if self.recorder.is_none() {
            let first = i64::from(frame_number);
            match Recorder::create(&self.path, labels.to_vec(), rate_hz, first) {
                Ok(r) => {
                    self.missing = vec![false; labels.len()];
                    self.recorder = Some(r);
                }
                Err(e) => return self.fail(&e),
            }
        }
        if xyz.len() != self.missing.len() * 3 {
            return;
        }
        let Some(r) = self.recorder.as_mut() else {
            return;
        };
        match r.push_frame(xyz, &self.missing) {
            Ok(()) => self.frames += 1,
            Err(e) => self.fail(&e),
        }
    }

    fn fail(&mut self, e: &replay::WriteError) {
        self.failed = true;
        tracing::warn!(path = %self.path.display(), error = %e, "recording stopped");
    }

    /// Frames recorded so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Closes the file complete; returns the frames written.
    ///
    /// # Errors
    /// [`RecordError::Write`] when the writer cannot finish the file.
    pub fn finish(self) -> Result<usize, RecordError> {
        let Some(r) = self.recorder else {
            return Ok(0);
        };
        let summary = r.finish().map_err(|e| RecordError::Write {
            path: self.path.display().to_string(),
            message: e.to_string(),
        })?;
        Ok(summary.frames as usize)
    }
}
