//! TRC and CSV: rows counted by their newlines, a last line without one being a row cut off
//! mid-write (unless a TRC header counts it), and the rewrite that keeps the whole rows.

use std::fs::File;
use std::io::{BufRead, BufReader, Read, Seek, SeekFrom, Write};
use std::path::Path;

use super::{Extent, RepairError};
use crate::trc::header::read_header;
use crate::trc::text::Lines;
use crate::Format;

/// Lines of a TRC header: file type, field names, field values, marker names, coordinates.
const TRC_HEADER_LINES: usize = 5;
/// The field-names and field-values lines of a TRC header (0-based).
const TRC_KEYS: usize = 1;
const TRC_VALUES: usize = 2;

/// Where a text take's header ends and its whole rows end.
#[derive(Debug)]
pub(super) struct Scan {
    pub(super) extent: Extent,
    /// The header's lines, raw (with their line ends).
    header: Vec<Vec<u8>>,
    /// Byte offset of the end of the header.
    header_end: u64,
    /// Byte offset after the last row kept.
    rows_end: u64,
    /// The last row kept is a TRC row without its newline, which the header counts.
    unterminated_kept: bool,
}

/// Scans a TRC or CSV file: the header read and checked, then every row counted.
///
/// # Errors
/// A header the reader refuses, or an I/O error.
pub(super) fn scan(file: &mut File, format: Format) -> Result<Scan, RepairError> {
    file.seek(SeekFrom::Start(0))?;
    let declared = match format {
        Format::Trc => Some(read_header(&mut Lines::new(BufReader::new(&mut *file)))?.num_frames),
        _ => {
            crate::csv::CsvBlocks::new(BufReader::new(&mut *file))?;
            None
        }
    };
    file.seek(SeekFrom::Start(0))?;
    let mut input = BufReader::new(&mut *file);
    let mut header = Vec::new();
    let mut offset = 0u64;
    let mut line = Vec::new();
    loop {
        line.clear();
        let n = input.read_until(b'\n', &mut line)?;
        if n == 0 {
            break;
        }
        offset += n as u64;
        header.push(line.clone());
        let done = match format {
            Format::Trc => header.len() == TRC_HEADER_LINES,
            // Comments and blank lines, then the column header.
            _ => !(is_blank(&line) || line.trim_ascii_start().starts_with(b"#")),
        };
        if done {
            break;
        }
    }
    let header_end = offset;
    let (mut rows, mut rows_end, mut torn_bytes, mut unterminated_kept) = (0, offset, 0, false);
    loop {
        line.clear();
        let n = input.read_until(b'\n', &mut line)?;
        if n == 0 {
            break;
        }
        offset += n as u64;
        if line.ends_with(b"\n") {
            rows += usize::from(!is_blank(&line));
            rows_end = offset;
        } else if !is_blank(&line) {
            // Only the last line can lack its newline.
            if declared.is_some_and(|d| rows < d) {
                rows += 1;
                rows_end = offset;
                unterminated_kept = true;
            } else {
                torn_bytes = n as u64;
            }
        }
    }
    Ok(Scan {
        extent: Extent {
            format,
            header_frames: declared,
            data_frames: rows,
            torn_bytes,
        },
        header,
        header_end,
        rows_end,
        unterminated_kept,
    })
}

fn is_blank(line: &[u8]) -> bool {
    line.iter().all(u8::is_ascii_whitespace)
}

/// Writes the whole rows of `path` to `target`: CSV cut after its last whole row, TRC with
/// its counts set to the rows kept. In place, CSV is cut where it is and TRC goes through a
/// temporary file beside it, renamed over it once on disk.
///
/// # Errors
/// As [`scan`], or an I/O error.
pub(super) fn rewrite(path: &Path, target: &Path, in_place: bool) -> Result<(), RepairError> {
    let mut file = File::open(path)?;
    let scan = scan(&mut file, Format::from_path(path).unwrap_or(Format::Csv))?;
    if scan.extent.format == Format::Csv && in_place {
        let file = std::fs::OpenOptions::new().write(true).open(path)?;
        file.set_len(scan.rows_end)?;
        file.sync_all()?;
        return Ok(());
    }
    let temp = in_place.then(|| {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy())
            .unwrap_or_default();
        path.with_file_name(format!(".{name}.repair"))
    });
    let dest = temp.as_deref().unwrap_or(target);
    let mut out = std::io::BufWriter::new(File::create(dest)?);
    match scan.extent.format {
        Format::Trc => {
            for (i, line) in scan.header.iter().enumerate() {
                if i == TRC_VALUES {
                    out.write_all(&counts_set(&scan.header, scan.extent.data_frames))?;
                } else {
                    out.write_all(line)?;
                }
            }
        }
        _ => scan.header.iter().try_for_each(|l| out.write_all(l))?,
    }
    file.seek(SeekFrom::Start(scan.header_end))?;
    let rows = scan.rows_end - scan.header_end;
    std::io::copy(&mut (&mut file).take(rows), &mut out)?;
    if scan.unterminated_kept {
        out.write_all(b"\n")?;
    }
    let out = out.into_inner().map_err(|e| e.into_error())?;
    out.sync_all()?;
    if let Some(temp) = &temp {
        std::fs::rename(temp, target)?;
        if let Some(dir) = target.parent().filter(|d| !d.as_os_str().is_empty()) {
            // The rename itself reaches the disk with its directory.
            File::open(dir).and_then(|d| d.sync_all()).ok();
        }
    }
    Ok(())
}

/// The TRC field-values line with `NumFrames` and `OrigNumFrames` set to `frames`, its line
/// end kept.
fn counts_set(header: &[Vec<u8>], frames: usize) -> Vec<u8> {
    let text = |i: usize| String::from_utf8_lossy(header.get(i).map_or(&[][..], |l| l));
    let keys = text(TRC_KEYS);
    let values = text(TRC_VALUES);
    let body = values.trim_end_matches(['\n', '\r']);
    let end = &values[body.len()..];
    let mut cells: Vec<String> = body.split('\t').map(str::to_owned).collect();
    for (column, key) in keys.trim_end().split('\t').enumerate() {
        let key = key.trim();
        if key.eq_ignore_ascii_case("NumFrames") || key.eq_ignore_ascii_case("OrigNumFrames") {
            if cells.len() <= column {
                cells.resize(column + 1, String::new());
            }
            cells[column] = frames.to_string();
        }
    }
    let mut line = cells.join("\t");
    line.push_str(end);
    line.into_bytes()
}
