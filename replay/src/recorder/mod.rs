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
//!   patched in place by [`Recorder::finish`] (readers trim the field).
//! - **C3D**: the parameter section is sized for a take longer than 65,535 frames (room for
//!   POINT:LONG_FRAMES) and rewritten in place, with the header, on finish.
//! - **CSV** has no count; rows are complete as they are written.
//!
//! Only one frame's bytes are held, in a reused buffer behind a [`BufWriter`]: memory does not
//! grow with the take, and [`Recorder::push_frame`] does not allocate once warm.
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
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use crate::c3d::write::{self as c3d, FrameRange, Meta};
use crate::c3d::C3dLimitError;
use crate::error::{TakeError, WriteError};
pub use crate::take::RecordTime;
use crate::trc::text::{check_labels, push_sample};
use crate::{Format, Take};

mod trc_header;
use trc_header::{trc_header, COUNT_WIDTH, RATE_WIDTH};

/// Write buffer: a few frames of a large layout, so the kernel sees few, large writes.
const BUFFER_BYTES: usize = 64 * 1024;

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
    /// `None` once finished.
    out: Option<BufWriter<File>>,
    labels: Vec<String>,
    rate_hz: f64,
    first_frame: i64,
    frames: u64,
    /// TRC: byte offsets of the `NumFrames` and `OrigNumFrames` placeholders.
    count_at: [u64; 2],
    /// C3D: parameter blocks reserved.
    c3d_blocks: usize,
    /// Timecode and measured rate.
    time: RecordTime,
    /// TRC: byte offset of the `CameraRate` placeholder.
    camera_rate_at: u64,
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
    /// cannot hold (a separator in a TRC/CSV label, C3D limits such as a first frame outside
    /// 0..=65535); or an I/O error creating the file.
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
        let out = BufWriter::with_capacity(BUFFER_BYTES, File::create(path)?);
        let mut rec = Recorder {
            path: path.to_path_buf(),
            format,
            out: Some(out),
            line: String::with_capacity(labels.len() * 40 + 40),
            bytes: Vec::with_capacity(labels.len() * 16),
            labels,
            rate_hz,
            first_frame,
            frames: 0,
            count_at: [0; 2],
            c3d_blocks,
            time,
            camera_rate_at: 0,
        };
        rec.write_header()?;
        Ok(rec)
    }

    /// Writes the header, with placeholder counts where the format needs them.
    fn write_header(&mut self) -> Result<(), WriteError> {
        let mut text = String::new();
        match self.format {
            Format::C3d => {
                // A provisional one-frame range: rewritten on finish.
                let bytes = c3d::head(
                    &self.meta(),
                    &FrameRange::new(self.first_frame, 1)?,
                    self.c3d_blocks,
                );
                self.writer().write_all(&bytes)?;
                return Ok(());
            }
            Format::Csv => {
                writeln!(text, "# rate_hz={} units=mm", self.rate_hz).expect("String write");
                text.push_str("frame,time");
                if self.time.timecode.is_some() {
                    text.push_str(",timecode");
                }
                for label in &self.labels {
                    for axis in ["x", "y", "z"] {
                        write!(text, ",{label}_{axis}").expect("String write");
                    }
                }
                text.push('\n');
            }
            Format::Trc => {
                let (rate, first, tc) = (self.rate_hz, self.first_frame, self.time.timecode);
                let at = trc_header(&mut text, &self.labels, (rate, first), tc.as_ref());
                [self.count_at[0], self.count_at[1], self.camera_rate_at] = at;
            }
        }
        self.writer().write_all(text.as_bytes())?;
        Ok(())
    }

    fn meta(&self) -> Meta<'_> {
        Meta {
            labels: &self.labels,
            rate_hz: self.rate_hz,
            time: Some(&self.time),
        }
    }

    /// Sets the measured rate written on finish (C3D `TRIAL:CAMERA_RATE`, TRC `CameraRate`).
    pub fn set_camera_rate(&mut self, rate_hz: f64) {
        if rate_hz.is_finite() && rate_hz > 0.0 {
            self.time.camera_rate_hz = Some(rate_hz);
        }
    }

    fn writer(&mut self) -> &mut BufWriter<File> {
        self.out
            .as_mut()
            .expect("a recorder is only used before finish consumes it")
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
                let written = self.writer().write_all(&bytes);
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
                let written = self.writer().write_all(line.as_bytes());
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

    /// Flushes, patches the counts into the header and closes the file.
    ///
    /// # Errors
    /// An I/O error, or [`C3dLimitError::NoFrames`] for a C3D recording of no frames (the file
    /// is removed: C3D cannot hold an empty take).
    pub fn finish(mut self) -> Result<RecordSummary, WriteError> {
        self.finalise()
    }

    fn finalise(&mut self) -> Result<RecordSummary, WriteError> {
        let Some(out) = self.out.take() else {
            return Err(std::io::Error::other("recording already finished").into());
        };
        let mut file = out.into_inner().map_err(|e| e.into_error())?;
        match self.format {
            Format::Csv => {}
            Format::Trc => {
                let count = format!("{:<COUNT_WIDTH$}", self.frames);
                for at in self.count_at {
                    file.seek(SeekFrom::Start(at))?;
                    file.write_all(count.as_bytes())?;
                }
                let rate = self.time.camera_rate_hz.unwrap_or(self.rate_hz);
                let mut rate = format!("{rate:.6}");
                rate.truncate(RATE_WIDTH);
                file.seek(SeekFrom::Start(self.camera_rate_at))?;
                file.write_all(format!("{rate:<RATE_WIDTH$}").as_bytes())?;
            }
            Format::C3d => self.patch_c3d(&mut file)?,
        }
        file.sync_data()?;
        Ok(RecordSummary {
            path: self.path.clone(),
            format: self.format,
            frames: self.frames,
            markers: self.labels.len(),
        })
    }

    /// Pads the data to whole blocks and rewrites header and parameters with the real range.
    fn patch_c3d(&self, file: &mut File) -> Result<(), WriteError> {
        let frames = self.frames as usize;
        let range = match FrameRange::new(self.first_frame, frames) {
            Ok(range) => range,
            Err(e) => {
                // An empty frame range is no C3D file: leave none rather than an unreadable one.
                let _ = std::fs::remove_file(&self.path);
                return Err(e.into());
            }
        };
        file.write_all(&vec![0u8; c3d::padding(frames, self.labels.len())])?;
        file.seek(SeekFrom::Start(0))?;
        file.write_all(&c3d::head(&self.meta(), &range, self.c3d_blocks))?;
        Ok(())
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        if self.out.is_some() {
            // Best effort: the owner did not call finish, so nobody can hear an error.
            let _ = self.finalise();
        }
    }
}
