//! Writing a take in blocks of frames ([`TakeWriter`]): the header first, then each block as it
//! comes, in bounded memory. With the frame count known up front the file is byte for byte
//! what [`crate::save`] writes for the whole take (the same header and row functions write
//! both); without it, TRC and C3D need a count in their header and are written by the
//! [`Recorder`], whose header is patched on finish (same data, padded header fields).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use crate::error::{TakeError, WriteError};
use crate::recorder::{Behind, Recorder};
use crate::{c3d, csv, trc, Format, Take};

/// Write buffer of the exact writer: large writes, few system calls.
const BUFFER_BYTES: usize = 256 * 1024;

/// A take file written block by block; see the module docs.
#[derive(Debug)]
pub struct TakeWriter(Inner);

#[derive(Debug)]
enum Inner {
    Exact(Exact),
    Recorder(Recorder),
}

/// The header of a known frame count, then rows as [`crate::save`] writes them.
#[derive(Debug)]
struct Exact {
    format: Format,
    out: BufWriter<File>,
    markers: usize,
    first_frame: i64,
    declared: usize,
    written: usize,
    line: String,
    bytes: Vec<u8>,
}

impl TakeWriter {
    /// Creates (truncates) `path`, its format from the extension, and writes the header of a
    /// take with these labels, rate and first frame, of `frames` frames when known.
    ///
    /// # Errors
    /// [`WriteError::UnknownFormat`], labels or rate that break a [`Take`] invariant, what the
    /// format cannot hold, or an I/O error.
    pub fn create(
        path: &Path,
        labels: &[String],
        (rate_hz, first_frame): (f64, i64),
        frames: Option<usize>,
    ) -> Result<TakeWriter, WriteError> {
        let format =
            Format::from_path(path).ok_or_else(|| WriteError::UnknownFormat(path.into()))?;
        let (frames, format) = match (frames, format) {
            (Some(n), _) => (n, format),
            (None, Format::Csv) => (0, format),
            (None, _) => {
                // Offline: frames can wait for the disk rather than stop the file.
                let rec = Recorder::create(path, labels.to_vec(), rate_hz, first_frame)?
                    .when_behind(Behind::Wait);
                return Ok(TakeWriter(Inner::Recorder(rec)));
            }
        };
        Take::new(labels.to_vec(), rate_hz, first_frame).validate()?;
        match format {
            Format::Trc => trc::check_labels(labels)?,
            Format::Csv => csv::check_labels(labels)?,
            Format::C3d => {}
        }
        let mut out = BufWriter::with_capacity(BUFFER_BYTES, File::create(path)?);
        match format {
            Format::C3d => {
                c3d::write::write_head(&mut out, labels, (rate_hz, first_frame), frames)?
            }
            Format::Trc => trc::write_header(&mut out, labels, (rate_hz, first_frame), frames)?,
            Format::Csv => csv::write_header(&mut out, labels, rate_hz)?,
        }
        Ok(TakeWriter(Inner::Exact(Exact {
            format,
            out,
            markers: labels.len(),
            first_frame,
            declared: frames,
            written: 0,
            line: String::new(),
            bytes: Vec::new(),
        })))
    }

    /// Appends the frames of `block` (its labels those given to [`TakeWriter::create`], its
    /// rate the take's).
    ///
    /// # Errors
    /// A block that breaks a [`Take`] invariant (a non-finite present sample, another marker
    /// count), more frames than declared, or an I/O error.
    pub fn write_block(&mut self, block: &Take) -> Result<(), WriteError> {
        block.validate()?;
        match &mut self.0 {
            Inner::Recorder(rec) => {
                for f in 0..block.n_frames() {
                    rec.push_frame(block.frame(f), block.frame_missing(f))?;
                }
            }
            Inner::Exact(w) => w.write_block(block)?,
        }
        Ok(())
    }

    /// Frames written so far.
    pub fn frames(&self) -> usize {
        match &self.0 {
            Inner::Recorder(rec) => rec.frames() as usize,
            Inner::Exact(w) => w.written,
        }
    }

    /// Ends the file (C3D padding, a recorder's patched header) and flushes it.
    ///
    /// # Errors
    /// [`WriteError::FrameCountMismatch`] when fewer frames were written than declared; an I/O
    /// error.
    pub fn finish(self) -> Result<(), WriteError> {
        match self.0 {
            Inner::Recorder(rec) => rec.finish().map(drop),
            Inner::Exact(mut w) => {
                if w.written != w.declared && w.format != Format::Csv {
                    let (declared, written) = (w.declared, w.written);
                    return Err(WriteError::FrameCountMismatch { declared, written });
                }
                if w.format == Format::C3d {
                    c3d::write::write_padding(&mut w.out, w.written, w.markers)?;
                }
                w.out.flush()?;
                Ok(())
            }
        }
    }
}

impl Exact {
    fn write_block(&mut self, block: &Take) -> Result<(), WriteError> {
        if block.n_markers() != self.markers {
            return Err(TakeError::ShapeMismatch {
                markers: self.markers,
                positions: block.positions.len(),
                mask: block.missing.len(),
            }
            .into());
        }
        let written = self.written + block.n_frames();
        if self.format != Format::Csv && written > self.declared {
            let declared = self.declared;
            return Err(WriteError::FrameCountMismatch { declared, written });
        }
        let at = (self.first_frame, self.written);
        match self.format {
            Format::C3d => c3d::write::write_frames(&mut self.out, block, &mut self.bytes)?,
            Format::Trc => trc::text::write_rows(&mut self.out, block, at, '\t', &mut self.line)?,
            Format::Csv => {
                crate::trc::text::write_rows(&mut self.out, block, at, ',', &mut self.line)?
            }
        }
        self.written = written;
        Ok(())
    }
}
