//! `/record/start <path>`: the edited stream (and optionally the raw input) written to C3D,
//! TRC or CSV by extension, closed complete on `/record/stop` or shutdown.

use std::path::{Path, PathBuf};

use replay::Take;

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

/// One recording in progress. Frames arrive in model order with the model's labels.
#[derive(Debug)]
pub struct Recording {
    path: PathBuf,
    take: Option<Take>,
    missing: Vec<bool>,
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
            take: None,
            missing: Vec::new(),
        })
    }

    /// Appends one edited frame; the first frame fixes labels, rate and first frame number.
    pub fn push(&mut self, labels: &[String], rate_hz: f64, frame_number: i32, xyz: &[f32]) {
        let take = self
            .take
            .get_or_insert_with(|| Take::new(labels.to_vec(), rate_hz, i64::from(frame_number)));
        if take.n_markers() * 3 != xyz.len() {
            return;
        }
        self.missing.resize(take.n_markers(), false);
        take.push_frame(xyz, &self.missing);
    }

    /// Frames recorded so far.
    pub fn frames(&self) -> usize {
        self.take.as_ref().map_or(0, Take::n_frames)
    }

    /// Writes the file complete; returns the frames written.
    ///
    /// # Errors
    /// [`RecordError::Write`] when the writer refuses the take.
    pub fn finish(self) -> Result<usize, RecordError> {
        let Some(take) = self.take else {
            return Ok(0);
        };
        replay::save(&self.path, &take).map_err(|e| RecordError::Write {
            path: self.path.display().to_string(),
            message: e.to_string(),
        })?;
        Ok(take.n_frames())
    }
}
