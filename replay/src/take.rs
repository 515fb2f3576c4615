//! The in-memory take: what every reader produces and every writer consumes.

use crate::error::{ReadError, TakeError};

/// Largest coordinate of a present sample, mm (10 km): no capture volume comes near it, so a
/// value past it is corrupt data, not a position ([`Take::validate`]).
pub const MAX_COORDINATE_MM: f32 = 1.0e7;

/// Length units a file may declare; everything in memory is millimetres.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Units {
    /// Millimetres (the in-memory unit).
    #[default]
    Millimetres,
    /// Centimetres (x10 on read).
    Centimetres,
    /// Metres (x1000 on read).
    Metres,
}

impl Units {
    /// Parses a units field such as `mm`, `cm`, `m` (case-insensitive, trimmed).
    pub fn parse(text: &str) -> Option<Units> {
        match text.trim().trim_matches('\0').to_ascii_lowercase().as_str() {
            "mm" | "millimeters" | "millimetres" => Some(Units::Millimetres),
            "cm" | "centimeters" | "centimetres" => Some(Units::Centimetres),
            "m" | "meters" | "metres" => Some(Units::Metres),
            _ => None,
        }
    }

    /// Factor that converts a value in these units to millimetres.
    pub fn to_mm(self) -> f32 {
        match self {
            Units::Millimetres => 1.0,
            Units::Centimetres => 10.0,
            Units::Metres => 1000.0,
        }
    }

    /// The short name written to files (`mm`, `cm`, `m`).
    pub fn as_str(self) -> &'static str {
        match self {
            Units::Millimetres => "mm",
            Units::Centimetres => "cm",
            Units::Metres => "m",
        }
    }
}

/// A recorded take: marker labels, frame rate, first frame number, positions in millimetres and a
/// per-sample missing mask.
///
/// Layout: `positions[(frame * n_markers + marker) * 3 + axis]` and
/// `missing[frame * n_markers + marker]`. A missing sample's position is stored as `0.0` and must
/// be ignored; the mask is authoritative.
#[derive(Debug, Clone, PartialEq)]
pub struct Take {
    /// Marker labels, one per marker, in file order.
    pub labels: Vec<String>,
    /// Frames per second.
    pub rate_hz: f64,
    /// Frame number of the first frame, as the file numbers it (C3D and TRC usually start at 1).
    pub first_frame: i64,
    /// Positions, frames x markers x 3, millimetres.
    pub positions: Vec<f32>,
    /// Missing mask, frames x markers.
    pub missing: Vec<bool>,
    /// Units the source file declared (values are already converted to millimetres).
    pub source_units: Units,
}

impl Take {
    /// An empty take with the given labels and rate.
    pub fn new(labels: Vec<String>, rate_hz: f64, first_frame: i64) -> Take {
        Take {
            labels,
            rate_hz,
            first_frame,
            positions: Vec::new(),
            missing: Vec::new(),
            source_units: Units::Millimetres,
        }
    }

    /// Number of markers.
    pub fn n_markers(&self) -> usize {
        self.labels.len()
    }

    /// Number of frames.
    pub fn n_frames(&self) -> usize {
        self.missing
            .len()
            .checked_div(self.n_markers())
            .unwrap_or(0)
    }

    /// Positions of one frame: markers x 3.
    ///
    /// # Panics
    /// If `frame >= self.n_frames()`.
    pub fn frame(&self, frame: usize) -> &[f32] {
        let w = self.n_markers() * 3;
        &self.positions[frame * w..(frame + 1) * w]
    }

    /// Missing mask of one frame: one flag per marker.
    ///
    /// # Panics
    /// If `frame >= self.n_frames()`.
    pub fn frame_missing(&self, frame: usize) -> &[bool] {
        let n = self.n_markers();
        &self.missing[frame * n..(frame + 1) * n]
    }

    /// Whether a sample is missing.
    pub fn is_missing(&self, frame: usize, marker: usize) -> bool {
        self.missing[frame * self.n_markers() + marker]
    }

    /// Position of one sample, `None` when missing.
    pub fn sample(&self, frame: usize, marker: usize) -> Option<[f32; 3]> {
        if self.is_missing(frame, marker) {
            return None;
        }
        let i = (frame * self.n_markers() + marker) * 3;
        Some([
            self.positions[i],
            self.positions[i + 1],
            self.positions[i + 2],
        ])
    }

    /// Appends one frame. `xyz` is markers x 3 (mm); `missing` one flag per marker. Positions of
    /// missing samples are stored as zero.
    ///
    /// # Panics
    /// If the slice lengths do not match the marker count.
    pub fn push_frame(&mut self, xyz: &[f32], missing: &[bool]) {
        let n = self.n_markers();
        assert_eq!(xyz.len(), n * 3, "frame must hold markers x 3 values");
        assert_eq!(missing.len(), n, "mask must hold one flag per marker");
        // Grown once and filled branch-free (one extend per marker was a cost of `edit`'s
        // output assembly, issue 35).
        let p0 = self.positions.len();
        self.positions.resize(p0 + n * 3, 0.0);
        let out = self.positions[p0..].chunks_exact_mut(3);
        for ((o, p), &gone) in out.zip(xyz.chunks_exact(3)).zip(missing) {
            for (o, &v) in o.iter_mut().zip(p) {
                *o = if gone { 0.0 } else { v };
            }
        }
        self.missing.extend_from_slice(missing);
    }

    /// Keeps frame indices `range` (0-based, clamped to the take) and drops the rest; the
    /// first frame number moves with the cut, so the kept frames keep their numbers.
    pub fn keep_frames(&mut self, range: std::ops::Range<usize>) {
        let n = self.n_markers();
        let end = range.end.min(self.n_frames());
        let start = range.start.min(end);
        self.positions.truncate(end * n * 3);
        self.positions.drain(..start * n * 3);
        self.missing.truncate(end * n);
        self.missing.drain(..start * n);
        self.first_frame += start as i64;
    }

    /// Time in seconds of frame index `frame` (0-based), counted from the first frame.
    pub fn time_of(&self, frame: usize) -> f64 {
        frame as f64 / self.rate_hz
    }

    /// Number of missing samples per marker.
    pub fn missing_per_marker(&self) -> Vec<usize> {
        let n = self.n_markers();
        let mut counts = vec![0; n];
        for (i, &gone) in self.missing.iter().enumerate() {
            if gone {
                counts[i % n] += 1;
            }
        }
        counts
    }

    /// Index of a marker by label.
    pub fn marker_index(&self, label: &str) -> Option<usize> {
        self.labels.iter().position(|l| l == label)
    }

    /// Checks the invariants every reader and writer relies on.
    ///
    /// # Errors
    /// A [`TakeError`] naming the broken invariant: buffer sizes, a non-finite or non-positive
    /// rate, a non-finite present sample or one past [`MAX_COORDINATE_MM`], duplicate or empty
    /// labels.
    pub fn validate(&self) -> Result<(), TakeError> {
        let n = self.n_markers();
        if n == 0 {
            return Err(TakeError::NoMarkers);
        }
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0) {
            return Err(TakeError::BadRate(self.rate_hz));
        }
        if self.missing.len() % n != 0 || self.positions.len() != self.missing.len() * 3 {
            return Err(TakeError::ShapeMismatch {
                markers: n,
                positions: self.positions.len(),
                mask: self.missing.len(),
            });
        }
        for (i, label) in self.labels.iter().enumerate() {
            if label.trim().is_empty() {
                return Err(TakeError::EmptyLabel { marker: i });
            }
            if self.labels[..i].contains(label) {
                return Err(TakeError::DuplicateLabel(label.clone()));
            }
        }
        // When every value (missing ones included) is finite and plausible, so is every present
        // sample: one pass the compiler vectorises (no early exit inside a chunk; NaN fails the
        // comparison); the loop below names the first bad one.
        let plausible = |c: &[f32]| {
            c.iter()
                .fold(true, |ok, v| ok & (v.abs() <= MAX_COORDINATE_MM))
        };
        if self.positions.chunks(4096).all(plausible) {
            return Ok(());
        }
        for (i, &gone) in self.missing.iter().enumerate() {
            if gone {
                continue;
            }
            let (frame, marker) = (i / n, || self.labels[i % n].clone());
            let xyz = &self.positions[i * 3..i * 3 + 3];
            if xyz.iter().any(|v| !v.is_finite()) {
                return Err(TakeError::NonFinite {
                    frame,
                    marker: marker(),
                });
            }
            if let Some(&value) = xyz.iter().find(|v| v.abs() > MAX_COORDINATE_MM) {
                return Err(TakeError::Implausible {
                    frame,
                    marker: marker(),
                    value,
                });
            }
        }
        Ok(())
    }
}

/// What a live recording knows besides labels, rate and first frame (issue 16).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RecordTime {
    /// The first frame's SMPTE timecode: in TRC's header (`Timecode`) and C3D's TIMECODE
    /// group; with it a CSV recording has a `timecode` column, one per frame.
    pub timecode: Option<protocol::Smpte>,
    /// The rate measured from the source (C3D `TRIAL:CAMERA_RATE`, TRC `CameraRate`); may
    /// also be set before finishing ([`crate::recorder::Recorder::set_camera_rate`]).
    pub camera_rate_hz: Option<f64>,
}

/// What a take file says before its frames.
#[derive(Debug, Clone, PartialEq)]
pub struct TakeHeader {
    /// Marker labels, in file order.
    pub labels: Vec<String>,
    /// Frame rate; `None` for a CSV file without `rate_hz`, whose rate is derived from its
    /// time column once every row is read.
    pub rate_hz: Option<f64>,
    /// Number of the first frame (1 for a file with no frames).
    pub first_frame: i64,
    /// Frames the file declares (C3D, TRC); `None` where the format does not say (CSV).
    pub frames: Option<usize>,
    /// Units the file declared (values are read in millimetres).
    pub source_units: Units,
}

impl TakeHeader {
    /// A take with no frames and this header's labels, rate (1 Hz when not yet known), first
    /// frame and units: the block buffer to pass to [`crate::blocks::BlockReader::read_block`].
    pub fn empty_take(&self) -> Take {
        let mut take = Take::new(
            self.labels.clone(),
            self.rate_hz.unwrap_or(1.0),
            self.first_frame,
        );
        take.source_units = self.source_units;
        take
    }

    /// Checks the header against the take invariants that do not depend on frames (labels,
    /// rate), so a block reader refuses a bad file before its first block.
    pub(crate) fn validate(&self) -> Result<(), ReadError> {
        self.empty_take().validate()?;
        Ok(())
    }
}
