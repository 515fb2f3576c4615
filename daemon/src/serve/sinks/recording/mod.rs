//! `/record/start <path> [<raw path>]`: the edited stream, and optionally the raw input beside
//! it, written to C3D, TRC or CSV by extension as frames arrive; closed complete on
//! `/record/stop` or shutdown.
//!
//! Each stream (source address + layout) gets its own files, so performers never mix: the
//! first stream seen writes to the paths given, the next ones to `<stem>.<k>.<ext>` with the
//! first `k` from 2 whose names are not taken by this recording. A stream whose labels change
//! mid-take (a model swap, a relabelled source) continues in a new numbered file. The edited
//! file holds the model's markers as sent (gaps filled by the model); the raw file holds
//! every marker the source sent, under its own labels, with its gaps, before any
//! stabilisation or glitch rejection. Both hold the frames the daemon processed for the
//! stream; frame numbers lost or dropped on the way are written as all-missing rows, so the
//! timing stays true.

use std::path::{Path, PathBuf};

mod file;
mod recorder;

use engine::{Processed, StreamKey};
use protocol::FrameBuf;

use self::file::{File, Frame};
pub use self::recorder::Recorder;

/// Why a recording could not start or finish.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// Not `.c3d`, `.trc` or `.csv`.
    #[error("{path}: record to a .c3d, .trc or .csv file")]
    Extension {
        /// The path.
        path: String,
    },
    /// The raw input would overwrite the edited stream.
    #[error("{path}: the raw input needs a path of its own")]
    SamePath {
        /// The path given twice.
        path: String,
    },
    /// The file exists and overwriting was not asked for.
    #[error("{path} exists; give overwrite (a last int 1) to replace it")]
    Exists {
        /// The path.
        path: String,
    },
    /// A recording to this path is running.
    #[error("already recording to {path}; /record/stop first, or start one with a new path")]
    Running {
        /// The path.
        path: String,
    },
    /// The file cannot be created or written.
    #[error("{path}")]
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

/// What a recording writes of one processed frame.
#[derive(Debug, Clone, Copy)]
pub struct RecordFrame<'a> {
    /// The stream.
    pub key: StreamKey,
    /// Its model labels (the edited file's columns).
    pub labels: &'a [String],
    /// The source's labels (the raw file's columns).
    pub input_labels: &'a [String],
    /// The model rate.
    pub rate_hz: f64,
    /// The frame number.
    pub frame_number: i32,
    /// Frame numbers since the stream's previous frame (1: none lost).
    pub frames_since_last: u32,
    /// The source's timecode.
    pub timecode: Option<&'a protocol::Smpte>,
    /// The edited positions, model order.
    pub xyz: &'a [f32],
    /// The frame as received, source order, with its gaps.
    pub input: &'a FrameBuf,
}

impl<'a> RecordFrame<'a> {
    /// What a recording writes of `e`.
    pub fn of(e: &'a Processed<'a>) -> RecordFrame<'a> {
        RecordFrame {
            key: e.key,
            labels: e.labels(),
            input_labels: e.input_labels(),
            rate_hz: e.rate_hz(),
            frame_number: e.frame_number(),
            frames_since_last: e.frames_since_last,
            timecode: e.time.timecode.as_ref(),
            xyz: e.xyz(),
            input: e.input,
        }
    }
}

/// One stream's files.
#[derive(Debug)]
struct StreamFiles {
    key: StreamKey,
    edited: File,
    raw: Option<File>,
}

impl StreamFiles {
    /// Whether these files were opened for a frame with these labels.
    fn fits(&self, e: &RecordFrame<'_>) -> bool {
        self.edited.labels == e.labels
            && self.raw.as_ref().is_none_or(|r| r.labels == e.input_labels)
    }
}

/// One recording in progress (bounded memory: [`replay::recorder::Recorder`] streams to disk).
#[derive(Debug)]
pub struct Recording {
    path: PathBuf,
    /// Files that exist may be replaced.
    overwrite: bool,
    raw: Option<PathBuf>,
    /// Files of streams still recording.
    streams: Vec<StreamFiles>,
    /// Files of streams whose labels changed: closed at the end.
    retired: Vec<StreamFiles>,
    /// Every path this recording writes, absolute, so no two files share one.
    taken: Vec<PathBuf>,
    /// The model has no gaps to mark in the edited stream: all `false`, grown as needed.
    no_gaps: Vec<bool>,
    /// The input's gaps, source order.
    input_gaps: Vec<bool>,
    /// Why a file stopped (a full disk): the file and the cause. The recording is over then;
    /// the processing thread closes it and tells the controller.
    stopped: Option<String>,
    /// Who started it over OSC, told by `/emoshift/error` if it stops by itself.
    controller: Option<std::net::SocketAddr>,
}

/// `path` made absolute (not resolving links), for comparing paths given differently.
fn absolute(path: &Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf())
}

/// `.c3d`, `.trc` or `.csv` (any case).
fn check_extension(path: &Path) -> Result<(), RecordError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("c3d" | "trc" | "csv")) {
        return Err(RecordError::Extension {
            path: path.display().to_string(),
        });
    }
    Ok(())
}

/// The file can be created, so `/record/start` answers with the error at once.
fn check_creatable(path: &Path) -> Result<(), RecordError> {
    std::fs::File::create(path).map_err(|source| RecordError::Io {
        path: path.display().to_string(),
        source,
    })?;
    Ok(())
}

/// The path of the `k`-th stream's file (`k` from 1): `path` itself for the first,
/// `<stem>.<k>.<ext>` after.
pub fn stream_path(path: &Path, k: usize) -> PathBuf {
    if k <= 1 {
        return path.to_path_buf();
    }
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy())
        .unwrap_or_default();
    let name = match path.extension() {
        Some(ext) => format!("{stem}.{k}.{}", ext.to_string_lossy()),
        None => format!("{stem}.{k}"),
    };
    path.with_file_name(name)
}

impl Recording {
    /// Checks both paths (extension, distinct, not there unless `overwrite`, can be created).
    ///
    /// # Errors
    /// [`RecordError::Extension`], [`RecordError::SamePath`], [`RecordError::Exists`] or
    /// [`RecordError::Io`].
    pub fn start(
        path: &Path,
        raw: Option<&Path>,
        overwrite: bool,
    ) -> Result<Recording, RecordError> {
        if raw.is_some_and(|raw| absolute(raw) == absolute(path)) {
            return Err(RecordError::SamePath {
                path: path.display().to_string(),
            });
        }
        // Every check before any file is created, so a refused start truncates nothing.
        check_extension(path)?;
        raw.map(check_extension).transpose()?;
        for p in std::iter::once(path).chain(raw) {
            // Opening a FIFO or a device to write would block or never end.
            if std::fs::metadata(p).is_ok_and(|m| !m.is_file()) {
                return Err(RecordError::Io {
                    path: p.display().to_string(),
                    source: std::io::Error::other("not a regular file"),
                });
            }
            if !overwrite && p.exists() {
                return Err(RecordError::Exists {
                    path: p.display().to_string(),
                });
            }
        }
        if let Some(raw) = raw {
            check_creatable(raw)?;
        }
        check_creatable(path)?;
        Ok(Recording {
            path: path.to_path_buf(),
            overwrite,
            raw: raw.map(Path::to_path_buf),
            streams: Vec::new(),
            retired: Vec::new(),
            taken: Vec::new(),
            no_gaps: Vec::new(),
            input_gaps: Vec::new(),
            stopped: None,
            controller: None,
        })
    }

    /// Names the OSC peer that started the recording, told if it stops by itself.
    pub fn told_to(mut self, controller: Option<std::net::SocketAddr>) -> Recording {
        self.controller = controller;
        self
    }

    /// The OSC peer that started the recording.
    pub fn controller(&self) -> Option<std::net::SocketAddr> {
        self.controller
    }

    /// Why the recording stopped by itself, naming the file, the frames it keeps and the
    /// cause ("live.c3d: stopped after 361 frames, which the file keeps: No space left on
    /// device (os error 28)"); `None` while it records.
    pub fn stopped(&self) -> Option<&str> {
        self.stopped.as_deref()
    }

    /// The edited stream's first file, and the raw input's, as given.
    pub fn paths(&self) -> (&Path, Option<&Path>) {
        (&self.path, self.raw.as_deref())
    }

    /// Whether this recording writes to `path` (its edited stream's first file).
    pub fn writes_to(&self, path: &Path) -> bool {
        absolute(path) == absolute(&self.path)
    }

    /// Appends one processed frame to its stream's files (opened on the stream's first frame).
    pub fn push(&mut self, e: &RecordFrame<'_>) {
        let i = match self.streams.iter().position(|s| s.key == e.key) {
            Some(i) if self.streams[i].fits(e) => i,
            Some(i) => {
                tracing::info!(target: "emoshift", source = %e.key.source, "labels changed: recording to new files");
                let old = self.streams.swap_remove(i);
                self.retired.push(old);
                self.open(e)
            }
            None => self.open(e),
        };
        let frame = Frame {
            rate_hz: e.rate_hz,
            number: e.frame_number,
            lost: e.frames_since_last.saturating_sub(1),
            timecode: e.timecode,
        };
        let markers = e.labels.len();
        if self.no_gaps.len() < markers {
            self.no_gaps.resize(markers, false);
        }
        let files = &mut self.streams[i];
        let gaps = &self.no_gaps[..markers];
        files.edited.push(frame, e.xyz, gaps);
        if let Some(raw) = files.raw.as_mut() {
            let n = e.input.marker_count();
            self.input_gaps.clear();
            self.input_gaps
                .extend((0..n).map(|i| e.input.is_missing(i)));
            let xyz = &e.input.positions()[..n * 3];
            raw.push(frame, xyz, &self.input_gaps);
        }
        if self.stopped.is_none() {
            let raw = files.raw.as_ref().and_then(File::stopped);
            if let Some((path, why)) = files.edited.stopped().or(raw) {
                self.stopped = Some(format!("{}: {why}", path.display()));
            }
        }
    }

    /// The first free name for a new stream's file.
    fn free_path(&mut self, base: &Path) -> PathBuf {
        let mut k = 1;
        loop {
            let p = stream_path(base, k);
            let abs = absolute(&p);
            // The first file was checked at start; later ones skip what is already on disk.
            let on_disk = k > 1 && !self.overwrite && p.exists();
            if !self.taken.contains(&abs) && !on_disk {
                self.taken.push(abs);
                return p;
            }
            k += 1;
        }
    }

    /// A new stream's files; its index.
    fn open(&mut self, e: &RecordFrame<'_>) -> usize {
        let key = e.key;
        let edited = self.free_path(&self.path.clone());
        let raw = self.raw.clone().map(|p| self.free_path(&p));
        tracing::info!(
            target: "emoshift",
            source = %key.source,
            layout = key.layout_id,
            edited = %edited.display(),
            raw = ?raw.as_ref().map(|p| p.display().to_string()),
            "recording a stream"
        );
        self.streams.push(StreamFiles {
            key,
            edited: File::new(edited, e.labels),
            raw: raw.map(|p| File::new(p, e.input_labels)),
        });
        self.streams.len() - 1
    }

    /// Closes every file complete; returns the edited frames written, over all streams.
    ///
    /// # Errors
    /// [`RecordError::Write`] of the first file the writer could not finish (the others are
    /// still closed).
    pub fn finish(self) -> Result<u64, RecordError> {
        let mut frames = 0;
        let mut first_error = None;
        for s in self.streams.into_iter().chain(self.retired) {
            for (file, edited) in std::iter::once((s.edited, true)).chain(s.raw.map(|r| (r, false)))
            {
                match file.finish() {
                    Ok(n) if edited => frames += n,
                    Ok(_) => {}
                    Err(e) => first_error = first_error.or(Some(e)),
                }
            }
        }
        first_error.map_or(Ok(frames), Err)
    }
}

#[cfg(test)]
mod tests;
