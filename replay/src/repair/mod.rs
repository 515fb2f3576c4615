//! Takes cut off by a crash: what a file holds past its header ([`inspect`]), and the repair
//! that makes the header count it ([`repair`]).
//!
//! A recording killed between two header updates holds more frames than its header counts
//! (the C3D header's frame range, TRC's `NumFrames`) and may end inside a frame: a torn C3D
//! record, or a last TRC or CSV row without its newline. The readers keep to the header and
//! stop before a torn row, so such a file reads as the frames its header counts; [`inspect`]
//! tells what more it holds and [`repair`] makes the header count every whole frame and drops
//! the torn one. emoshift's [`crate::recorder::Recorder`] keeps the header at most a second
//! behind the data; files of builds before it said one frame until they were closed.
//!
//! ```
//! use replay::repair;
//!
//! let dir = tempfile::tempdir().expect("temp dir");
//! let path = dir.path().join("cut.csv");
//! std::fs::write(&path, "# rate_hz=100 units=mm\nframe,time,A_x,A_y,A_z\n1,0,1,2,3\n2,0.01,1,2")
//!     .expect("written");
//! let extent = repair::inspect(&path).expect("inspected");
//! assert_eq!((extent.data_frames, extent.problem().is_some()), (1, true));
//! let repaired = repair::repair(&path, None).expect("repaired");
//! assert_eq!(repaired.frames, 1);
//! assert!(repair::inspect(&path).expect("inspected").problem().is_none());
//! ```

mod text;

use std::fs::OpenOptions;
use std::path::{Path, PathBuf};

use crate::error::ReadError;
use crate::Format;

/// What a take file's header counts and what its data holds.
#[derive(Debug, Clone, PartialEq)]
pub struct Extent {
    /// The file's format.
    pub format: Format,
    /// Frames the header counts (`None` for CSV, which has no count).
    pub header_frames: Option<usize>,
    /// Whole frames of data: C3D records, TRC and CSV rows ended by a newline (and a last TRC
    /// row without one that the header counts).
    pub data_frames: usize,
    /// Bytes of a frame cut off mid-write after the last whole one (0 when there is none).
    pub torn_bytes: u64,
}

impl Extent {
    /// What is wrong, for a warning (`None` when the header and data agree and nothing is
    /// torn): "holds 363 frames, header says 1", "its last row is cut off (17 bytes without a
    /// newline)".
    pub fn problem(&self) -> Option<String> {
        let mut parts = Vec::new();
        match self.header_frames {
            Some(h) if h < self.data_frames => {
                parts.push(format!(
                    "holds {} frames, header says {h}",
                    self.data_frames
                ));
            }
            Some(h) if h > self.data_frames => {
                parts.push(format!(
                    "header says {h} frames, the data holds {}",
                    self.data_frames
                ));
            }
            _ => {}
        }
        if self.torn_bytes > 0 {
            parts.push(match self.format {
                Format::C3d => format!(
                    "its last frame is cut off ({} bytes of a record)",
                    self.torn_bytes
                ),
                Format::Trc | Format::Csv => format!(
                    "its last row is cut off ({} bytes without a newline)",
                    self.torn_bytes
                ),
            });
        }
        (!parts.is_empty()).then(|| parts.join("; "))
    }
}

/// Why a file could not be inspected or repaired.
#[derive(Debug, thiserror::Error)]
pub enum RepairError {
    /// The extension names no take format.
    #[error("unknown take format {0:?} (expected .c3d, .trc or .csv)")]
    UnknownFormat(PathBuf),
    /// The header cannot be read: there is nothing to count frames against.
    #[error("the header cannot be read")]
    Read(#[from] ReadError),
    /// Not a regular file, or it cannot be opened.
    #[error(transparent)]
    Open(#[from] crate::file::OpenError),
    /// An I/O error.
    #[error("cannot read or write the file")]
    Io(#[from] std::io::Error),
    /// Not one whole frame: nothing a reader could be given.
    #[error("no whole frame to keep: a take needs at least one")]
    NoFrames,
    /// A C3D range past the header's 16-bit last frame, in a file with no
    /// TRIAL:ACTUAL_END_FIELD to hold it.
    #[error(
        "frames {first}..{last} pass the c3d header's 16-bit last frame, and this file has no \
         TRIAL:ACTUAL_END_FIELD to count them"
    )]
    NoRoom {
        /// First frame.
        first: i64,
        /// Last frame.
        last: i64,
    },
    /// The repaired file does not read back with the frames kept (a damaged row before the
    /// end, say).
    #[error("the repaired file does not read back")]
    Verify(#[source] ReadError),
}

impl From<crate::c3d::extent::PatchError> for RepairError {
    fn from(e: crate::c3d::extent::PatchError) -> RepairError {
        use crate::c3d::extent::PatchError;
        match e {
            PatchError::NoFrames => RepairError::NoFrames,
            PatchError::NoRoom { first, last } => RepairError::NoRoom { first, last },
            PatchError::Io(e) => RepairError::Io(e),
        }
    }
}

/// What [`repair`] did.
#[derive(Debug, Clone, PartialEq)]
pub struct Repaired {
    /// The file as it was.
    pub before: Extent,
    /// Frames the repaired file holds.
    pub frames: usize,
    /// The file written (the input itself, or the `out` given); `None` when there was nothing
    /// to repair and nothing was written.
    pub written: Option<PathBuf>,
}

/// Measures what `path` holds against what its header says; reads the header and scans the
/// data (C3D: only the last records).
///
/// # Errors
/// [`RepairError::UnknownFormat`], a header the readers refuse ([`RepairError::Read`]), or an
/// I/O error.
pub fn inspect(path: &Path) -> Result<Extent, RepairError> {
    let format = Format::from_path(path).ok_or_else(|| RepairError::UnknownFormat(path.into()))?;
    // Only a regular file: a link to /dev/zero would be scanned forever, a FIFO would block.
    let mut file = crate::file::open_bounded(path, u64::MAX)?.into_inner();
    match format {
        Format::C3d => {
            let e = crate::c3d::extent::measure(&mut file)?;
            Ok(Extent {
                format,
                header_frames: Some(e.header_frames),
                data_frames: e.data_frames,
                torn_bytes: e.torn_bytes,
            })
        }
        Format::Trc | Format::Csv => Ok(text::scan(&mut file, format)?.extent),
    }
}

/// Makes the header of `path` count every whole frame its data holds and drops a torn last
/// frame: in place, or into `out` (created or replaced; `path` is not changed). C3D is patched
/// in place (header and parameter counts, the data cut after the last whole frame); TRC is
/// rewritten with its `NumFrames` and `OrigNumFrames` (through a temporary file beside it when
/// in place); CSV is cut after its last whole row. The result is read back before returning.
/// A file with nothing to repair is left alone, and `out` not written.
///
/// # Errors
/// As [`inspect`]; [`RepairError::NoFrames`] when no whole frame is left;
/// [`RepairError::NoRoom`]; [`RepairError::Verify`] when the repaired file does not read
/// back with the frames kept; an I/O error.
pub fn repair(path: &Path, out: Option<&Path>) -> Result<Repaired, RepairError> {
    let before = inspect(path)?;
    if before.problem().is_none() {
        return Ok(Repaired {
            frames: before.data_frames,
            before,
            written: None,
        });
    }
    if before.data_frames == 0 {
        return Err(RepairError::NoFrames);
    }
    let target = out.unwrap_or(path).to_path_buf();
    let in_place = out.is_none_or(|o| same_file(o, path));
    match before.format {
        Format::C3d => {
            if !in_place {
                std::fs::copy(path, &target)?;
            }
            let mut file = OpenOptions::new().read(true).write(true).open(&target)?;
            let extent = crate::c3d::extent::measure(&mut file)?;
            crate::c3d::extent::patch(&mut file, &extent, extent.data_frames)?;
        }
        Format::Trc | Format::Csv => text::rewrite(path, &target, in_place)?,
    }
    let take = crate::load(&target).map_err(RepairError::Verify)?;
    if take.n_frames() != before.data_frames {
        let (declared, found) = (before.data_frames, take.n_frames());
        return Err(RepairError::Verify(ReadError::FrameCountMismatch {
            declared,
            found,
        }));
    }
    Ok(Repaired {
        frames: before.data_frames,
        before,
        written: Some(target),
    })
}

/// Whether two paths name one file (an `out` equal to the input means in place).
fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}
