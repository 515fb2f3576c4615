//! TRC takes: the tab-separated OpenSim / Motion Analysis layout.
//!
//! ```text
//! PathFileType  4  (X/Y/Z)  take.trc
//! DataRate  CameraRate  NumFrames  NumMarkers  Units  OrigDataRate  OrigDataStartFrame  OrigNumFrames
//! 60.00     60.00       962        41          mm     60.00         1                   962
//! Frame#  Time  ForeHead_M  <empty>  <empty>  ForeHead_L  <empty>  <empty> ...
//!               X1          Y1       Z1       X2          Y2       Z2 ...
//! <blank line, optional>
//! 1       0.000000  143.5201  842.2137  29.0542  185.6148 ...
//! ```
//!
//! Reading rules (every violation is a typed [`ReadError`] naming the line, and the column and
//! marker where there is one; nothing panics on bad input):
//! - Cells are separated by single tabs; CRLF line ends, blank lines and trailing empty cells are
//!   tolerated.
//! - `Units` `mm`, `cm` or `m`; values are converted to millimetres and the declared units kept in
//!   [`Take::source_units`]. Other units are [`ReadError::UnknownUnits`].
//! - A blank or `NaN` cell means missing; a marker is missing in a frame if any of its three cells
//!   is. `inf` or text is [`ReadError::BadCell`].
//! - A row shorter than the header means its trailing markers are missing, as long as it stops at
//!   a marker boundary (or ends in an empty cell) and ends in a newline; a row that stops after a
//!   marker's x or y value, or a short last row with no newline (a file cut off mid-write), is
//!   [`ReadError::TruncatedRow`]. Non-empty cells beyond the header are
//!   [`ReadError::ColumnCount`].
//! - The first row's `Frame#` is the take's first frame; later rows must count up by one
//!   ([`ReadError::FrameGap`]). The `Time` column must be a number but is otherwise not used: the
//!   rate is `DataRate`.
//! - `NumMarkers` must equal the names listed ([`ReadError::MarkerCountMismatch`]). `NumFrames`
//!   rows are read: fewer is [`ReadError::FrameCountMismatch`] (a truncated file: accepting it
//!   would silently lose frames); rows past it are not read, as a C3D reader keeps to its
//!   header's range. Those are a recording's last frames, written after its header was last
//!   updated: [`crate::repair`] tells and counts them (`emoshift info` warns, `emoshift repair`
//!   fixes the header).
//!
//! Writing always uses millimetres, the shortest decimal text that reads back to the same `f32`
//! (round trips are exact), times to the microsecond, and empty cells for missing samples.

pub(crate) mod header;
pub(crate) mod row_blocks;
mod rows;
pub(crate) mod text;

use std::io::{BufReader, Read, Write};

pub use self::rows::TrcBlocks;
use crate::error::{ReadError, WriteError};
use crate::Take;

/// Reads a TRC take (values converted to millimetres): the block reader run to the end.
///
/// # Errors
/// I/O failure, malformed or truncated content (see the module docs for each rule), unknown
/// units, or a take that breaks a [`Take`] invariant (no markers, duplicate labels).
pub fn read(input: impl Read) -> Result<Take, ReadError> {
    let mut blocks = TrcBlocks::new(BufReader::new(input))?;
    let mut take = blocks.header().empty_take();
    // Reading to the end runs the end-of-file checks (the frame count).
    blocks.read_block(usize::MAX, &mut take)?;
    take.validate()?;
    Ok(take)
}

/// Writes a TRC take in millimetres.
///
/// # Errors
/// A take that breaks a [`Take`] invariant, a label holding a tab or line break
/// ([`WriteError::LabelUnrepresentable`]), or I/O failure. Nothing is written when the take or a
/// label is rejected.
pub fn write(take: &Take, out: &mut impl Write) -> Result<(), WriteError> {
    take.validate()?;
    check_labels(&take.labels)?;
    let (rate, first) = (take.rate_hz, take.first_frame);
    write_header(out, &take.labels, (rate, first), take.n_frames())?;
    text::write_rows(out, take, (first, 0), '\t', &mut String::new())?;
    Ok(())
}

/// Rejects labels TRC cannot hold (a tab or line break).
pub(crate) fn check_labels(labels: &[String]) -> Result<(), WriteError> {
    text::check_labels(labels, "trc", &['\t', '\n', '\r'])
}

/// The five header lines of a take of `frames` frames, and the blank line before the rows.
pub(crate) fn write_header(
    out: &mut impl Write,
    labels: &[String],
    (rate, first): (f64, i64),
    frames: usize,
) -> std::io::Result<()> {
    let n = labels.len();
    writeln!(out, "PathFileType\t4\t(X/Y/Z)\ttake.trc")?;
    writeln!(
        out,
        "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames"
    )?;
    writeln!(
        out,
        "{rate}\t{rate}\t{frames}\t{n}\tmm\t{rate}\t{first}\t{frames}"
    )?;
    let mut line = String::from("Frame#\tTime");
    for label in labels {
        line.push('\t');
        line.push_str(label);
        line.push_str("\t\t");
    }
    writeln!(out, "{line}")?;
    line.clear();
    line.push('\t');
    for k in 1..=n {
        line.push_str(&format!("\tX{k}\tY{k}\tZ{k}"));
    }
    writeln!(out, "{line}\n")
}
