//! One file of a recording ([`File`]): opened on its stream's first frame (labels, rate, first
//! frame number and timecode), lost frames written as all-missing rows, a write error kept
//! for the close.

use std::path::PathBuf;

use protocol::Smpte;
use replay::recorder::{RecordTime, Recorder};

use super::RecordError;

/// Lost frame numbers filled with all-missing rows at most (a minute at 120 Hz); a longer
/// pause is written as if it had not happened, and logged.
const MAX_FILL: u32 = 7_200;

/// What a file needs of a frame besides its samples.
#[derive(Debug, Clone, Copy)]
pub(super) struct Frame<'a> {
    pub(super) rate_hz: f64,
    pub(super) number: i32,
    /// Frame numbers lost before it, written as all-missing rows.
    pub(super) lost: u32,
    pub(super) timecode: Option<&'a Smpte>,
}

/// One file being written, opened on its first frame (which fixes labels, rate and the first
/// frame number). A write error stops this file (logged once, reported when it is closed);
/// what was written stays.
#[derive(Debug)]
pub(super) struct File {
    path: PathBuf,
    pub(super) labels: Vec<String>,
    recorder: Option<Recorder>,
    error: Option<String>,
    gaps: Vec<bool>,
    blank: Vec<f32>,
}

impl File {
    pub(super) fn new(path: PathBuf, labels: &[String]) -> File {
        File {
            path,
            labels: labels.to_vec(),
            recorder: None,
            error: None,
            gaps: vec![true; labels.len()],
            blank: vec![0.0; labels.len() * 3],
        }
    }

    /// Appends one frame (with its timecode), after `lost` all-missing rows.
    pub(super) fn push(&mut self, frame: Frame<'_>, xyz: &[f32], gaps: &[bool]) {
        let Frame {
            rate_hz,
            number,
            lost,
            timecode,
        } = frame;
        if self.error.is_some() || xyz.len() != self.labels.len() * 3 {
            return;
        }
        if self.recorder.is_none() {
            let time = RecordTime {
                timecode: timecode.copied(),
                camera_rate_hz: None,
            };
            let (labels, first) = (self.labels.clone(), i64::from(number));
            match Recorder::create_timed(&self.path, labels, rate_hz, first, time) {
                Ok(r) => self.recorder = Some(r),
                Err(e) => return self.fail(&e),
            }
        } else if lost > MAX_FILL {
            tracing::warn!(target: "emoshift", path = %self.path.display(), lost, "long pause not filled: the take jumps over it; if the source paused, start a new recording after a pause");
        } else {
            for _ in 0..lost {
                if let Some(Err(e)) = self
                    .recorder
                    .as_mut()
                    .map(|r| r.push_frame(&self.blank, &self.gaps))
                {
                    return self.fail(&e);
                }
            }
        }
        if let Some(Err(e)) = self
            .recorder
            .as_mut()
            .map(|r| r.push_frame_timed(xyz, gaps, timecode))
        {
            self.fail(&e);
        }
    }

    fn fail(&mut self, e: &replay::WriteError) {
        tracing::warn!(target: "emoshift", path = %self.path.display(), error = %e, "recording stopped: the file holds the frames before it; free space or record to another disk, then /record/start again");
        self.error = Some(e.to_string());
    }

    /// Why this file stopped (a full disk, a write error: the writer's message, naming the
    /// frames kept and the OS's cause), and its path; `None` while it records.
    pub(super) fn stopped(&self) -> Option<(&std::path::Path, &str)> {
        self.error.as_deref().map(|e| (self.path.as_path(), e))
    }

    /// Closes the file; frames written.
    pub(super) fn finish(self) -> Result<u64, RecordError> {
        let write_error = |message: String| RecordError::Write {
            path: self.path.display().to_string(),
            message,
        };
        let frames = match self.recorder {
            Some(r) => r.finish().map_err(|e| write_error(e.to_string()))?.frames,
            None => 0,
        };
        tracing::info!(target: "emoshift", path = %self.path.display(), frames, "recording closed");
        match self.error {
            Some(e) => Err(write_error(format!("stopped after {frames} frames: {e}"))),
            None => Ok(frames),
        }
    }
}
