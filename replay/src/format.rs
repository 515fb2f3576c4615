//! Format dispatch by file extension, and whole-file load/save.

use std::fs::File;
use std::io::{BufReader, BufWriter, Write};
use std::path::Path;

use crate::error::{ReadError, WriteError};
use crate::{c3d, csv, trc, Take};

/// The take formats emoshift reads and writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// C3D (read by emoshift's decoder, cross-checked by c3dio; written by [`crate::c3d::write`]
    /// as Intel float32).
    C3d,
    /// TRC, the OpenSim / Motion Analysis text layout.
    Trc,
    /// CSV: `frame,time,<label>_x,<label>_y,<label>_z,...`.
    Csv,
}

impl Format {
    /// The format a path's extension names, if any (case-insensitive).
    pub fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        Format::from_name(&ext)
    }

    /// The format named `c3d`, `trc` or `csv` (case-insensitive).
    pub fn from_name(name: &str) -> Option<Format> {
        match name.to_ascii_lowercase().as_str() {
            "c3d" => Some(Format::C3d),
            "trc" => Some(Format::Trc),
            "csv" => Some(Format::Csv),
            _ => None,
        }
    }

    /// The file extension, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            Format::C3d => "c3d",
            Format::Trc => "trc",
            Format::Csv => "csv",
        }
    }
}

/// Reads a take from a file, choosing the format by extension.
///
/// # Errors
/// [`ReadError::UnknownFormat`] for an unsupported extension, otherwise whatever the format's
/// reader reports (I/O, malformed or truncated content, invalid values).
pub fn load(path: &Path) -> Result<Take, ReadError> {
    load_limited(path, crate::file::DEFAULT_MAX_TAKE_BYTES)
}

/// [`load`] of a regular file of at most `max_bytes`.
///
/// # Errors
/// As [`load`]; [`ReadError::Open`] for a device, a FIFO or a file past the limit.
pub fn load_limited(path: &Path, max_bytes: u64) -> Result<Take, ReadError> {
    load_with(path, max_bytes, C3dDecoding::CrossChecked)
}

/// How [`load_with`] decodes the points of a C3D file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum C3dDecoding {
    /// emoshift's own decoder, cross-checked by c3dio on a sample of frames ([`c3d::read`]).
    #[default]
    CrossChecked,
    /// emoshift's own decoder alone ([`c3d::read_own`]): the same take, without the
    /// cross-check.
    Own,
}

/// [`load_limited`], decoding C3D points as `decoding` says (other formats ignore it).
///
/// # Errors
/// As [`load_limited`].
pub fn load_with(path: &Path, max_bytes: u64, decoding: C3dDecoding) -> Result<Take, ReadError> {
    let format = Format::from_path(path).ok_or_else(|| ReadError::UnknownFormat(path.into()))?;
    let reader = BufReader::new(crate::file::open_bounded(path, max_bytes)?);
    let take = match (format, decoding) {
        (Format::C3d, C3dDecoding::CrossChecked) => c3d::read(reader)?,
        (Format::C3d, C3dDecoding::Own) => c3d::read_own(reader)?,
        (Format::Trc, _) => trc::read(reader)?,
        (Format::Csv, _) => csv::read(reader)?,
    };
    take.validate()?;
    Ok(take)
}

/// Writes a take to a file, choosing the format by extension.
///
/// # Errors
/// [`WriteError::UnknownFormat`] for an unsupported extension, an invalid take, or I/O failure.
pub fn save(path: &Path, take: &Take) -> Result<(), WriteError> {
    let format = Format::from_path(path).ok_or_else(|| WriteError::UnknownFormat(path.into()))?;
    take.validate()?;
    let mut out = BufWriter::new(File::create(path)?);
    write_as(format, take, &mut out)?;
    out.flush()?;
    Ok(())
}

/// Writes a take in the given format to any writer.
///
/// # Errors
/// An invalid take, a take the format cannot hold, or I/O failure.
pub fn write_as(format: Format, take: &Take, out: &mut impl Write) -> Result<(), WriteError> {
    match format {
        Format::C3d => c3d::write(take, out),
        Format::Trc => trc::write(take, out),
        Format::Csv => csv::write(take, out),
    }
}
