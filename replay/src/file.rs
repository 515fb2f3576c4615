//! Opening input files safely: only regular files are read (a FIFO would block forever, a
//! device such as `/dev/zero` never ends), and at most a size limit, read through a
//! [`std::io::Take`] so that a file growing while it is read still stops at the limit.

use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

/// Default limit of a take file: an hour at 120 Hz of 109 markers is about 1 GB as text.
pub const DEFAULT_MAX_TAKE_BYTES: u64 = 8 << 30;
/// Default limit of a text file read whole (manifests, region maps, configs).
pub const DEFAULT_MAX_TEXT_BYTES: u64 = 64 << 20;

/// Why an input file was not opened.
#[derive(Debug, thiserror::Error)]
pub enum OpenError {
    /// The file cannot be opened or its metadata read.
    #[error("cannot open {path:?}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A FIFO, a device, a socket or a directory.
    #[error("{path:?} is not a regular file but a {kind}")]
    NotAFile {
        /// The file.
        path: PathBuf,
        /// What it is.
        kind: &'static str,
    },
    /// Larger than the limit.
    #[error("{path:?} is {bytes} bytes, over the limit of {max}")]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Its size.
        bytes: u64,
        /// The limit.
        max: u64,
    },
}

/// What a non-regular file is, for the error.
fn kind_of(meta: &std::fs::Metadata) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_fifo() {
            return "fifo";
        }
        if t.is_char_device() {
            return "character device";
        }
        if t.is_block_device() {
            return "block device";
        }
        if t.is_socket() {
            return "socket";
        }
    }
    if meta.is_dir() {
        "directory"
    } else {
        "special file"
    }
}

/// Opens `path` for reading if it is a regular file (links followed) of at most `max` bytes.
///
/// # Errors
/// [`OpenError`] naming the file.
pub fn open_bounded(path: &Path, max: u64) -> Result<std::io::Take<File>, OpenError> {
    let io = |source| OpenError::Io {
        path: path.into(),
        source,
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        return Err(OpenError::NotAFile {
            path: path.into(),
            kind: kind_of(&meta),
        });
    }
    if meta.len() > max {
        return Err(OpenError::TooLarge {
            path: path.into(),
            bytes: meta.len(),
            max,
        });
    }
    let file = File::open(path).map_err(io)?;
    // One byte past the limit, so a file that grew is seen as too large, not cut short.
    Ok(file.take(max.saturating_add(1)))
}

/// Reads a text file of at most `max` bytes whole.
///
/// # Errors
/// [`OpenError`]; invalid UTF-8 and a file that grew past `max` are I/O errors.
pub fn read_to_string_bounded(path: &Path, max: u64) -> Result<String, OpenError> {
    let mut text = String::new();
    let read = open_bounded(path, max)?
        .read_to_string(&mut text)
        .map_err(|source| OpenError::Io {
            path: path.into(),
            source,
        })?;
    if read as u64 > max {
        return Err(OpenError::TooLarge {
            path: path.into(),
            bytes: read as u64,
            max,
        });
    }
    Ok(text)
}

#[cfg(test)]
mod tests;
