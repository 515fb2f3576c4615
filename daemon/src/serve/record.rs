//! `/record/start <path> [<raw path>]`: the edited stream, and optionally the raw input beside
//! it, written to C3D, TRC or CSV by extension as frames arrive; closed complete on
//! `/record/stop` or shutdown.
//!
//! Each stream (source address + layout) gets its own files, so performers never mix: the
//! first stream seen writes to the paths given, the k-th to `<stem>.<k>.<ext>`. The edited
//! file holds the model's markers as sent (gaps filled by the model); the raw file holds
//! every marker the source sent, under its own labels, with its gaps, before any
//! stabilisation or glitch rejection: nothing the stage sent is lost.

use std::path::{Path, PathBuf};

use replay::record::Recorder;

use super::pipeline::Emitted;
use super::streams::StreamKey;

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

/// One file being written, opened on its first frame (which fixes labels, rate and the first
/// frame number). A write error stops this file (logged once); what was written stays.
#[derive(Debug)]
struct Sink {
    path: PathBuf,
    recorder: Option<Recorder>,
    failed: bool,
}

impl Sink {
    fn new(path: PathBuf) -> Sink {
        Sink {
            path,
            recorder: None,
            failed: false,
        }
    }

    fn push(&mut self, labels: &[String], rate_hz: f64, first: i32, xyz: &[f32], gaps: &[bool]) {
        if self.failed || xyz.len() != labels.len() * 3 || gaps.len() != labels.len() {
            return;
        }
        if self.recorder.is_none() {
            match Recorder::create(&self.path, labels.to_vec(), rate_hz, i64::from(first)) {
                Ok(r) => self.recorder = Some(r),
                Err(e) => return self.fail(&e),
            }
        }
        if let Some(r) = self.recorder.as_mut() {
            if let Err(e) = r.push_frame(xyz, gaps) {
                self.fail(&e);
            }
        }
    }

    fn fail(&mut self, e: &replay::WriteError) {
        self.failed = true;
        tracing::warn!(path = %self.path.display(), error = %e, "recording stopped");
    }

    /// Closes the file; frames written.
    fn finish(self) -> Result<u64, RecordError> {
        let Some(r) = self.recorder else {
            return Ok(0);
        };
        let summary = r.finish().map_err(|e| RecordError::Write {
            path: self.path.display().to_string(),
            message: e.to_string(),
        })?;
        tracing::info!(path = %self.path.display(), frames = summary.frames, "recording closed");
        Ok(summary.frames)
    }
}

/// One stream's files.
#[derive(Debug)]
struct StreamFiles {
    key: StreamKey,
    edited: Sink,
    raw: Option<Sink>,
}

/// One recording in progress (bounded memory: [`Recorder`] streams to disk).
#[derive(Debug)]
pub struct Recording {
    path: PathBuf,
    raw: Option<PathBuf>,
    streams: Vec<StreamFiles>,
    /// The model has no gaps to mark in the edited stream: all `false`, grown as needed.
    no_gaps: Vec<bool>,
    /// The input's gaps, source order.
    input_gaps: Vec<bool>,
}

/// `.c3d`, `.trc` or `.csv` (any case), and the file can be created, so `/record/start`
/// answers with the error at once, not at the end.
fn check(path: &Path) -> Result<(), RecordError> {
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
    /// Checks both paths (extension, distinct, can be created).
    ///
    /// # Errors
    /// [`RecordError::Extension`], [`RecordError::SamePath`] or [`RecordError::Io`].
    pub fn start(path: &Path, raw: Option<&Path>) -> Result<Recording, RecordError> {
        if raw == Some(path) {
            return Err(RecordError::SamePath {
                path: path.display().to_string(),
            });
        }
        check(path)?;
        if let Some(raw) = raw {
            check(raw)?;
        }
        Ok(Recording {
            path: path.to_path_buf(),
            raw: raw.map(Path::to_path_buf),
            streams: Vec::new(),
            no_gaps: Vec::new(),
            input_gaps: Vec::new(),
        })
    }

    /// Appends one processed frame to its stream's files (opened on the stream's first frame).
    pub fn push(&mut self, e: &Emitted<'_>) {
        let i = match self.streams.iter().position(|s| s.key == e.key) {
            Some(i) => i,
            None => self.open(e.key),
        };
        if self.no_gaps.len() < e.labels.len() {
            self.no_gaps.resize(e.labels.len(), false);
        }
        let files = &mut self.streams[i];
        let gaps = &self.no_gaps[..e.labels.len()];
        files
            .edited
            .push(e.labels, e.rate_hz, e.frame_number, e.xyz, gaps);
        if let Some(raw) = files.raw.as_mut() {
            let n = e.input.marker_count();
            self.input_gaps.clear();
            self.input_gaps
                .extend((0..n).map(|i| e.input.is_missing(i)));
            let xyz = &e.input.positions()[..n * 3];
            raw.push(
                e.input_labels,
                e.rate_hz,
                e.frame_number,
                xyz,
                &self.input_gaps,
            );
        }
    }

    /// A new stream's files; its index.
    fn open(&mut self, key: StreamKey) -> usize {
        let k = self.streams.len() + 1;
        let edited = stream_path(&self.path, k);
        let raw = self.raw.as_deref().map(|p| stream_path(p, k));
        tracing::info!(
            source = %key.source,
            layout = key.layout_id,
            edited = %edited.display(),
            raw = ?raw.as_ref().map(|p| p.display().to_string()),
            "recording a stream"
        );
        self.streams.push(StreamFiles {
            key,
            edited: Sink::new(edited),
            raw: raw.map(Sink::new),
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
        for s in self.streams {
            for (sink, edited) in std::iter::once((s.edited, true)).chain(s.raw.map(|r| (r, false)))
            {
                match sink.finish() {
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
mod tests {
    use std::net::SocketAddr;

    use super::*;

    #[test]
    fn later_streams_get_numbered_files_beside_the_first() {
        let p = Path::new("/tmp/take.c3d");
        assert_eq!(stream_path(p, 1), PathBuf::from("/tmp/take.c3d"));
        assert_eq!(stream_path(p, 3), PathBuf::from("/tmp/take.3.c3d"));
        assert_eq!(
            stream_path(Path::new("out/a.v1.trc"), 2),
            PathBuf::from("out/a.v1.2.trc")
        );
    }

    #[test]
    fn bad_paths_are_refused_at_start() {
        let dir = tempfile::tempdir().expect("temp dir");
        let ok = dir.path().join("a.csv");
        assert!(matches!(
            Recording::start(&dir.path().join("a.txt"), None),
            Err(RecordError::Extension { .. })
        ));
        assert!(matches!(
            Recording::start(&ok, Some(&ok)),
            Err(RecordError::SamePath { .. })
        ));
        assert!(matches!(
            Recording::start(&ok, Some(&dir.path().join("missing/raw.c3d"))),
            Err(RecordError::Io { .. })
        ));
        assert!(Recording::start(&ok, Some(&dir.path().join("raw.trc"))).is_ok());
    }

    fn emitted<'a>(
        key: StreamKey,
        n: i32,
        labels: &'a [String],
        xyz: &'a [f32],
        input: &'a protocol::FrameBuf,
    ) -> Emitted<'a> {
        Emitted {
            key,
            frame_number: n,
            compact: &[],
            parts: &[],
            part_ends: &[],
            components: &[],
            xyz,
            input,
            input_labels: labels,
            labels,
            rate_hz: 60.0,
        }
    }

    #[test]
    fn two_performers_are_recorded_to_their_own_files_never_mixed() {
        let dir = tempfile::tempdir().expect("temp dir");
        let (edited, raw) = (dir.path().join("take.csv"), dir.path().join("in.csv"));
        let mut rec = Recording::start(&edited, Some(&raw)).expect("paths are fine");
        let labels: Vec<String> = vec!["a".into(), "b".into()];
        let key = |port| StreamKey {
            source: SocketAddr::from(([127, 0, 0, 1], port)),
            layout_id: 0,
        };
        let mut input = protocol::FrameBuf::with_max_markers(2);
        for n in 0..5 {
            for (k, port) in [(1.0, 7000), (2.0, 7001)] {
                let xyz = [k, 0.0, 0.0, k, 1.0, 0.0];
                input.set_frame(n, 0, &xyz).expect("finite");
                input.set_missing(1, n == 2);
                rec.push(&emitted(key(port), n, &labels, &xyz, &input));
            }
        }
        assert_eq!(rec.finish().expect("closes"), 10);
        for (path, k, gaps) in [
            (edited.clone(), 1.0, false),
            (stream_path(&edited, 2), 2.0, false),
            (raw.clone(), 1.0, true),
            (stream_path(&raw, 2), 2.0, true),
        ] {
            let take = replay::load(&path).expect("loads");
            assert_eq!(take.n_frames(), 5, "{}", path.display());
            assert!(take.frame(4)[..3] == [k, 0.0, 0.0], "{}", path.display());
            assert_eq!(take.is_missing(2, 1), gaps, "{}", path.display());
        }
    }
}
