//! Each format's header as frames are written: the C3D header and parameter section
//! rewritten for the new range (only the bytes that changed), TRC's `NumFrames`,
//! `OrigNumFrames` and `CameraRate` placeholders, nothing for CSV.

use std::fs::File;
use std::io::{Seek, SeekFrom, Write};
use std::path::Path;

use super::Header;
use crate::c3d::write::{self as c3d, FrameRange, Meta};

/// Width of the TRC frame-count placeholder: any `u64` fits.
pub(crate) const COUNT_WIDTH: usize = 20;
/// Width of the TRC `CameraRate` placeholder, patched with the measured rate on finish.
pub(crate) const RATE_WIDTH: usize = 20;
use crate::take::RecordTime;

/// Writes `bytes` at `at`.
fn put(file: &mut File, at: u64, bytes: &[u8]) -> std::io::Result<()> {
    file.seek(SeekFrom::Start(at))?;
    file.write_all(bytes)
}

/// Whole frames of `frame_bytes` bytes at the start of `bytes`: how many, and their length.
fn whole_records(bytes: &[u8], frame_bytes: usize) -> (u64, usize) {
    let frames = bytes.len() / frame_bytes.max(1);
    (frames as u64, frames * frame_bytes)
}

/// Whole rows (ended by a newline) at the start of `bytes`: how many, and their length.
fn whole_rows(bytes: &[u8]) -> (u64, usize) {
    let rows = bytes.iter().filter(|&&b| b == b'\n').count();
    let len = bytes.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
    (rows as u64, len)
}

/// A C3D recording's header and parameter section.
#[derive(Debug)]
pub(crate) struct C3dCount {
    pub(crate) labels: Vec<String>,
    pub(crate) rate_hz: f64,
    pub(crate) first_frame: i64,
    pub(crate) time: RecordTime,
    /// Parameter blocks reserved (for the longest range, so a count never moves the data).
    pub(crate) blocks: usize,
    /// Bytes of one frame record.
    pub(crate) frame_bytes: usize,
    /// The header and parameters as on disk, to write only what a new count changes.
    pub(crate) on_disk: Vec<u8>,
}

impl Header for C3dCount {
    fn count(
        &mut self,
        file: &mut File,
        frames: u64,
        camera_rate_hz: Option<f64>,
    ) -> std::io::Result<()> {
        if let Some(rate) = camera_rate_hz {
            self.time.camera_rate_hz = Some(rate);
        }
        let range =
            FrameRange::new(self.first_frame, frames as usize).map_err(std::io::Error::other)?;
        let meta = Meta {
            labels: &self.labels,
            rate_hz: self.rate_hz,
            time: Some(&self.time),
        };
        let head = c3d::head(&meta, &range, self.blocks);
        // Only the runs of bytes that changed: the counts, a few words each, seldom more (the
        // parameter section grows by POINT:LONG_FRAMES past 65535 frames).
        let mut at = 0;
        while at < head.len() {
            if self.on_disk.get(at) == Some(&head[at]) {
                at += 1;
                continue;
            }
            let end = (at..head.len())
                .find(|&i| self.on_disk.get(i) == Some(&head[i]))
                .unwrap_or(head.len());
            put(file, at as u64, &head[at..end])?;
            at = end;
        }
        self.on_disk = head;
        Ok(())
    }

    fn whole(&self, bytes: &[u8]) -> (u64, usize) {
        whole_records(bytes, self.frame_bytes)
    }

    fn close(&mut self, file: &mut File, path: &Path, frames: u64) -> std::io::Result<()> {
        if frames == 0 {
            // An empty frame range is no C3D file: leave none rather than an unreadable one.
            return std::fs::remove_file(path);
        }
        // Zero padding to a whole block: some readers expect it.
        let end = file.stream_position()?;
        file.set_len(end + c3d::padding(frames as usize, self.labels.len()) as u64)
    }
}

/// A TRC recording's counts and camera rate, blank-padded placeholders rewritten in place.
#[derive(Debug)]
pub(crate) struct TrcCount {
    /// Byte offsets of `NumFrames` and `OrigNumFrames`.
    pub(crate) count_at: [u64; 2],
    /// Byte offset of `CameraRate`.
    pub(crate) camera_rate_at: u64,
    /// `CameraRate` when no rate was measured.
    pub(crate) rate_hz: f64,
    /// The count and rate fields as on disk.
    pub(crate) on_disk: (String, String),
}

impl Header for TrcCount {
    fn count(
        &mut self,
        file: &mut File,
        frames: u64,
        camera_rate_hz: Option<f64>,
    ) -> std::io::Result<()> {
        let count = format!("{frames:<COUNT_WIDTH$}");
        if count != self.on_disk.0 {
            for at in self.count_at {
                put(file, at, count.as_bytes())?;
            }
            self.on_disk.0 = count;
        }
        let mut rate = format!("{:.6}", camera_rate_hz.unwrap_or(self.rate_hz));
        rate.truncate(RATE_WIDTH);
        let rate = format!("{rate:<RATE_WIDTH$}");
        if rate != self.on_disk.1 {
            put(file, self.camera_rate_at, rate.as_bytes())?;
            self.on_disk.1 = rate;
        }
        Ok(())
    }

    fn whole(&self, bytes: &[u8]) -> (u64, usize) {
        whole_rows(bytes)
    }

    fn close(&mut self, _: &mut File, _: &Path, _: u64) -> std::io::Result<()> {
        Ok(())
    }
}

/// A CSV recording: no count to keep, rows whole by their newlines.
#[derive(Debug)]
pub(crate) struct CsvRows;

impl Header for CsvRows {
    fn count(&mut self, _: &mut File, _: u64, _: Option<f64>) -> std::io::Result<()> {
        Ok(())
    }

    fn whole(&self, bytes: &[u8]) -> (u64, usize) {
        whole_rows(bytes)
    }

    fn close(&mut self, _: &mut File, _: &Path, _: u64) -> std::io::Result<()> {
        Ok(())
    }
}
