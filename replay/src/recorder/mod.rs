//! A streaming recorder: writes a take to C3D, TRC or CSV frame by frame, in bounded memory.
//!
//! ```
//! use replay::recorder::Recorder;
//!
//! let dir = tempfile::tempdir().expect("temp dir");
//! let path = dir.path().join("live.trc");
//! let labels = vec!["Chin".to_string(), "Nose".to_string()];
//! let mut rec = Recorder::create(&path, labels, 120.0, 1).expect("file created");
//! rec.push_frame(&[1.0, 2.0, 3.0, 0.0, 0.0, 0.0], &[false, true]).expect("frame written");
//! let summary = rec.finish().expect("file complete");
//! assert_eq!(summary.frames, 1);
//! let take = replay::load(&path).expect("a valid take");
//! assert_eq!((take.n_frames(), take.sample(0, 1)), (1, None));
//! ```
//!
//! The file holds exactly what [`crate::save`] writes for the same take, byte for byte in the
//! data; only the headers differ where a count is not known until the end:
//! - **TRC**: `NumFrames` and `OrigNumFrames` are written as a blank-padded placeholder and
//!   patched in place as frames reach the disk, and on finish (readers trim the field).
//! - **C3D**: the parameter section is sized for a take longer than 65,535 frames (room for
//!   POINT:LONG_FRAMES) and rewritten in place, with the header, as frames reach the disk (only
//!   the bytes that change) and on finish.
//! - **CSV** has no count; rows are complete as they are written.
//!
//! **Crash-safe.** The file is written on its own thread: [`Recorder::push_frame`] encodes the
//! frame and copies it to that thread's buffer, and never waits on the disk. That thread writes
//! what arrived every 0.2 s, and every 0.4 s makes it durable (`fdatasync`) and then updates the
//! header's count (C3D's frame range, TRC's `NumFrames`) to the frames on disk. After SIGKILL a
//! reader sees every frame but those of the last half second; after a power cut, every frame
//! but those of the last second (with a disk that syncs within a tenth of a second). Frames
//! written after the last count are there for [`crate::repair`] (`emoshift repair`). A CSV row
//! is written whole with its newline, and a last row without one reads as the end of the take.
//! Only [`Recorder::create`] (the file created and its header written) touches the disk on the
//! caller's thread.
//!
//! **Write errors** (a full disk): the file is closed valid with the whole frames that fit
//! (the header counting them), and every later push returns [`WriteError::Stopped`] naming the
//! cause and the frames kept. A disk that falls 64 MiB behind stops the recording the same way
//! (or, with [`Behind::Wait`], makes the caller wait), so memory stays bounded.
//!
//! Memory does not grow with the take, and [`Recorder::push_frame`] does not allocate once the
//! buffers shared with the file's thread have grown to a flush's worth of frames.
//!
//! **Zero frames.** TRC and CSV recordings of no frames are valid files that load as a take with
//! no frames (a CSV cannot store the first frame number without rows: it reads back as 1). C3D
//! cannot hold an empty frame range, so [`Recorder::finish`] removes the file and returns
//! [`C3dLimitError::NoFrames`].
//!
//! **Dropped without finish.** `Drop` finishes the file on a best-effort basis (errors are
//! ignored), so an early return or a panic unwinding through the owner still leaves a readable
//! file. Call [`Recorder::finish`] to learn whether it worked.

use std::fmt::Write as _;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::c3d::write::{self as c3d, FrameRange, Meta};
use crate::c3d::C3dLimitError;
use crate::durable::{C3dCount, CsvRows, DurableFile, Header, Stopped, TrcCount};
use crate::error::{TakeError, WriteError};
pub use crate::take::RecordTime;
use crate::trc::text::{check_labels, push_sample};
use crate::{Format, Take};

pub use crate::durable::{Behind, FLUSH, SYNC};

mod csv_header;
pub(crate) mod trc_header;
use csv_header::csv_header;
use trc_header::{trc_header, COUNT_WIDTH, RATE_WIDTH};

/// What a finished recording holds.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordSummary {
    /// The file written.
    pub path: PathBuf,
    /// Its format.
    pub format: Format,
    /// Frames written.
    pub frames: u64,
    /// Markers per frame.
    pub markers: usize,
}

/// A take being written as it arrives. See the module docs.
#[derive(Debug)]
pub struct Recorder {
    path: PathBuf,
    format: Format,
    /// The file, written on its own thread; `None` once finished.
    out: Option<DurableFile>,
    labels: Vec<String>,
    rate_hz: f64,
    first_frame: i64,
    frames: u64,
    /// Timecode and measured rate.
    time: RecordTime,
    /// One formatted row (text formats), reused.
    line: String,
    /// One encoded frame (C3D), reused.
    bytes: Vec<u8>,
}

impl Recorder {
    /// Creates (truncates) `path` and writes the header; the format comes from the extension.
    ///
    /// # Errors
    /// [`WriteError::UnknownFormat`] for another extension; [`WriteError::Invalid`] for no labels,
    /// an empty or repeated label or a rate that is not positive and finite; what the format
    /// cannot hold (a separator in a TRC/CSV label, C3D limits such as a negative first frame);
    /// or an I/O error creating the file.
    pub fn create(
        path: &Path,
        labels: Vec<String>,
        rate_hz: f64,
        first_frame: i64,
    ) -> Result<Recorder, WriteError> {
        Recorder::create_timed(path, labels, rate_hz, first_frame, RecordTime::default())
    }

    /// [`Recorder::create`] with the first frame's timecode and a measured rate (see
    /// [`RecordTime`]).
    ///
    /// # Errors
    /// As [`Recorder::create`].
    pub fn create_timed(
        path: &Path,
        labels: Vec<String>,
        rate_hz: f64,
        first_frame: i64,
        time: RecordTime,
    ) -> Result<Recorder, WriteError> {
        let format =
            Format::from_path(path).ok_or_else(|| WriteError::UnknownFormat(path.into()))?;
        let probe = Take::new(labels, rate_hz, first_frame);
        probe.validate()?;
        let labels = probe.labels;
        let mut c3d_blocks = 0;
        match format {
            Format::Trc => check_labels(&labels, "trc", &['\t', '\n', '\r'])?,
            Format::Csv => check_labels(&labels, "csv", &[',', '"', '\n', '\r'])?,
            Format::C3d => {
                c3d::check_labels(&labels)?;
                // Room for a camera rate set later.
                let reserve = RecordTime {
                    camera_rate_hz: time.camera_rate_hz.or(Some(rate_hz)),
                    ..time
                };
                let meta = Meta {
                    labels: &labels,
                    rate_hz,
                    time: Some(&reserve),
                };
                c3d_blocks = c3d::parameter_blocks(&meta, &FrameRange::longest(first_frame)?)?;
            }
        }
        let (head, header) = header(format, &labels, (rate_hz, first_frame), &time, c3d_blocks)?;
        let mut file = File::create(path)?;
        file.write_all(&head)?;
        let out = DurableFile::start(file, path, header, Behind::Stop)?;
        Ok(Recorder {
            path: path.to_path_buf(),
            format,
            out: Some(out),
            line: String::with_capacity(labels.len() * 40 + 40),
            bytes: Vec::with_capacity(labels.len() * 16),
            labels,
            rate_hz,
            first_frame,
            frames: 0,
            time,
        })
    }

    /// What to do when the disk falls 64 MiB behind: stop the recording (the default, for a
    /// live source that must never wait) or make [`Recorder::push_frame`] wait (an offline
    /// writer).
    pub fn when_behind(mut self, behind: Behind) -> Recorder {
        if let Some(out) = self.out.as_mut() {
            out.behind = behind;
        }
        self
    }

    /// Sets the measured rate written on the next header update (C3D `TRIAL:CAMERA_RATE`, TRC
    /// `CameraRate`).
    pub fn set_camera_rate(&mut self, rate_hz: f64) {
        if rate_hz.is_finite() && rate_hz > 0.0 {
            self.time.camera_rate_hz = Some(rate_hz);
            if let Some(out) = &self.out {
                out.set_camera_rate(rate_hz);
            }
        }
    }

    /// Hands one encoded frame to the file's thread.
    fn append(&mut self, frame: &[u8]) -> Result<(), WriteError> {
        let out = self
            .out
            .as_ref()
            .expect("a recorder is only used before finish consumes it");
        out.append(frame).map_err(stopped)
    }

    /// Appends one frame: `xyz` is markers × 3 in millimetres, `missing` one flag per marker
    /// (positions of missing markers are ignored).
    ///
    /// # Errors
    /// [`WriteError::Invalid`] for slices of the wrong length or a present sample that is not
    /// finite (nothing is written for that frame), [`WriteError::C3dLimit`] past the 32-bit
    /// frame numbers of C3D, or an I/O error.
    pub fn push_frame(&mut self, xyz: &[f32], missing: &[bool]) -> Result<(), WriteError> {
        self.push_frame_timed(xyz, missing, None)
    }

    /// [`Recorder::push_frame`] with the frame's timecode, for the CSV `timecode` column (a
    /// frame without one leaves its cell empty; other formats keep only the first frame's).
    ///
    /// # Errors
    /// As [`Recorder::push_frame`].
    pub fn push_frame_timed(
        &mut self,
        xyz: &[f32],
        missing: &[bool],
        timecode: Option<&protocol::Smpte>,
    ) -> Result<(), WriteError> {
        let n = self.labels.len();
        if xyz.len() != n * 3 || missing.len() != n {
            return Err(TakeError::ShapeMismatch {
                markers: n,
                positions: xyz.len(),
                mask: missing.len(),
            }
            .into());
        }
        let frame = self.frames as usize;
        let bad =
            (0..n).find(|&m| !missing[m] && xyz[m * 3..m * 3 + 3].iter().any(|v| !v.is_finite()));
        if let Some(m) = bad {
            let marker = self.labels[m].clone();
            return Err(TakeError::NonFinite { frame, marker }.into());
        }
        match self.format {
            Format::C3d => {
                if self.first_frame + self.frames as i64 >= i64::from(u32::MAX) {
                    let (first, last) = (self.first_frame, self.first_frame + self.frames as i64);
                    return Err(C3dLimitError::TooManyFrames { first, last }.into());
                }
                let mut bytes = std::mem::take(&mut self.bytes);
                c3d::encode_frame(xyz, missing, &mut bytes);
                let written = self.append(&bytes);
                self.bytes = bytes;
                written?;
            }
            Format::Trc | Format::Csv => {
                let sep = if self.format == Format::Trc {
                    '\t'
                } else {
                    ','
                };
                let mut line = std::mem::take(&mut self.line);
                let tc = (self.format == Format::Csv && self.time.timecode.is_some())
                    .then_some(timecode);
                self.format_row(&mut line, sep, (xyz, missing), tc);
                let written = self.append(line.as_bytes());
                self.line = line;
                written?;
            }
        }
        self.frames += 1;
        Ok(())
    }

    /// One text row, as `trc::write` and `csv::write` format it.
    /// `timecode`: `Some` when the row has a timecode cell (empty for `Some(None)`).
    fn format_row(
        &self,
        line: &mut String,
        sep: char,
        (xyz, missing): (&[f32], &[bool]),
        timecode: Option<Option<&protocol::Smpte>>,
    ) {
        line.clear();
        let number = self.first_frame.wrapping_add(self.frames as i64);
        let time = self.frames as f64 / self.rate_hz;
        write!(line, "{number}{sep}{time:.6}").expect("writing to a String cannot fail");
        if let Some(tc) = timecode {
            line.push(sep);
            if let Some(tc) = tc {
                write!(line, "{tc}").expect("writing to a String cannot fail");
            }
        }
        for (p, &gone) in xyz.chunks_exact(3).zip(missing) {
            for &v in p {
                line.push(sep);
                if !gone {
                    push_sample(line, v);
                }
            }
        }
        line.push('\n');
    }

    /// Frames written so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Writes what is left, updates the header's counts, closes and syncs the file.
    ///
    /// # Errors
    /// [`WriteError::Stopped`] when the file stopped on a write error before (it is closed
    /// valid with the frames that fit) or the close fails; [`C3dLimitError::NoFrames`] for a
    /// C3D recording of no frames (the file is removed: C3D cannot hold an empty take).
    pub fn finish(mut self) -> Result<RecordSummary, WriteError> {
        let out = self
            .out
            .take()
            .expect("a recorder is only used before finish consumes it");
        let frames = out.finish().map_err(stopped)?;
        if frames == 0 && self.format == Format::C3d {
            return Err(C3dLimitError::NoFrames.into());
        }
        Ok(RecordSummary {
            path: self.path.clone(),
            format: self.format,
            frames,
            markers: self.labels.len(),
        })
    }
}

fn stopped(s: Stopped) -> WriteError {
    WriteError::Stopped {
        frames: s.frames,
        cause: s.cause,
    }
}

/// The header of a new recording (placeholder counts where the format has them), and what
/// updates it as frames are written.
fn header(
    format: Format,
    labels: &[String],
    (rate_hz, first_frame): (f64, i64),
    time: &RecordTime,
    c3d_blocks: usize,
) -> Result<(Vec<u8>, Box<dyn Header>), WriteError> {
    let mut text = String::new();
    match format {
        Format::C3d => {
            let meta = Meta {
                labels,
                rate_hz,
                time: Some(time),
            };
            // A provisional one-frame range, rewritten once frames are on disk.
            let head = c3d::head(&meta, &FrameRange::new(first_frame, 1)?, c3d_blocks);
            let count = C3dCount {
                labels: labels.to_vec(),
                rate_hz,
                first_frame,
                time: *time,
                blocks: c3d_blocks,
                frame_bytes: labels.len() * 16,
                on_disk: head.clone(),
            };
            Ok((head, Box::new(count)))
        }
        Format::Csv => {
            csv_header(&mut text, labels, rate_hz, time.timecode.is_some());
            Ok((text.into_bytes(), Box::new(CsvRows)))
        }
        Format::Trc => {
            let tc = time.timecode;
            let at = trc_header(&mut text, labels, (rate_hz, first_frame), tc.as_ref());
            let count = TrcCount {
                count_at: [at[0], at[1]],
                camera_rate_at: at[2],
                rate_hz,
                on_disk: (
                    format!("{:<COUNT_WIDTH$}", 0),
                    format!("{:<RATE_WIDTH$}", format!("{rate_hz}")),
                ),
            };
            Ok((text.into_bytes(), Box::new(count)))
        }
    }
}
