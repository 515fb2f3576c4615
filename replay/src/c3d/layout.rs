//! Where the 3D points are and how they are stored, from the header and parameters, with every
//! cross-check a damaged file can fail.

use super::binary::{Header, Processor, BLOCK};
use super::params::Params;
use crate::error::c3d::C3dError;
use crate::error::ReadError;
use crate::Units;

/// The validated description of a file's 3D point data.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    /// Byte order and float format.
    pub processor: Processor,
    /// Points per frame.
    pub points: usize,
    /// Analog samples per frame (all channels), interleaved after the points.
    pub analog_per_frame: usize,
    /// Analog samples per frame as the parameters claim them: the header's samples per channel
    /// times ANALOG:USED (`analog_per_frame` in a consistent file). c3dio sizes its analog grid
    /// by it; emoshift reads nothing else from it.
    pub analog_claimed: usize,
    /// Float32 storage (header scale negative) rather than scaled int16.
    pub float: bool,
    /// Magnitude of the point scale: int16 values are multiplied by it.
    pub scale: f32,
    /// First frame number.
    pub first_frame: i64,
    /// Number of frames.
    pub frames: usize,
    /// Byte offset of the first frame.
    pub data_offset: usize,
    /// Frame rate in Hz.
    pub rate_hz: f64,
    /// Units of the stored coordinates.
    pub units: Units,
    /// One label per point.
    pub labels: Vec<String>,
    /// Inconsistencies tolerated because the rest of the file settles them (e.g. POINT:FRAMES
    /// disagreeing with a header frame range that the data length confirms).
    pub warnings: Vec<C3dError>,
}

impl Layout {
    /// Bytes in one stored value (int16 or float32).
    pub fn word(&self) -> usize {
        if self.float {
            4
        } else {
            2
        }
    }

    /// Bytes in one frame: points x 4 words plus the analog samples.
    pub fn frame_bytes(&self) -> usize {
        (self.points * 4 + self.analog_per_frame) * self.word()
    }

    /// Builds and checks the layout against the file length.
    ///
    /// # Errors
    /// Any [`C3dError`] describing an inconsistency, or unknown units.
    pub fn new(
        p: Processor,
        h: &Header,
        params: &Params,
        file_len: usize,
    ) -> Result<Layout, ReadError> {
        let points = point_count(h, params)?;
        let (scale, float) = scale(h, params)?;
        let (first_frame, frames, frames_warning) = frame_range(h, params)?;
        let data_block = data_block(h, params)?;
        let mut layout = Layout {
            processor: p,
            points,
            analog_per_frame: usize::from(h.analog_per_frame),
            analog_claimed: analog_claimed(h, params),
            float,
            scale,
            first_frame,
            frames,
            data_offset: (data_block - 1) * BLOCK,
            rate_hz: rate(h, params)?,
            units: units(params)?,
            labels: labels(params, points),
            warnings: frames_warning.into_iter().collect(),
        };
        let needed = frames.saturating_mul(layout.frame_bytes());
        let available = file_len.saturating_sub(layout.data_offset);
        if available < needed {
            return Err(C3dError::Truncated {
                first: first_frame,
                last: first_frame + frames as i64 - 1,
                needed,
                available,
                data_block,
            }
            .into());
        }
        layout.labels.truncate(points);
        Ok(layout)
    }
}

/// The header's analog samples per channel times ANALOG:USED (read unsigned, as the largest a
/// reader could take it for); none without the parameter.
fn analog_claimed(h: &Header, params: &Params) -> usize {
    let used = params.number("ANALOG", "USED", true).unwrap_or(0.0);
    // A float parameter may hold anything: c3dio converts it to u16.
    let used = used.clamp(0.0, f64::from(u16::MAX)) as usize;
    usize::from(h.analog_per_channel) * used
}

fn point_count(h: &Header, params: &Params) -> Result<usize, C3dError> {
    let header = usize::from(h.points);
    match params.number("POINT", "USED", true) {
        Some(used) if used as usize != header => Err(C3dError::PointCountMismatch {
            used: used as usize,
            header,
        }),
        _ if header == 0 => Err(C3dError::NoPoints),
        _ => Ok(header),
    }
}

fn scale(h: &Header, params: &Params) -> Result<(f32, bool), C3dError> {
    let mut s = h.scale;
    if s == 0.0 || !s.is_finite() {
        s = params.number("POINT", "SCALE", false).unwrap_or(0.0) as f32;
    }
    if s == 0.0 || !s.is_finite() {
        return Err(C3dError::BadScale(h.scale));
    }
    Ok((s.abs(), s < 0.0))
}

fn rate(h: &Header, params: &Params) -> Result<f64, C3dError> {
    let ok = |r: f32| r.is_finite() && r > 0.0;
    // Rates are stored as f32: take the shortest decimal that round-trips (65.05, not
    // 65.0533447265625), which is what the writing program meant.
    let exact = |r: f32| r.to_string().parse::<f64>().unwrap_or(f64::from(r));
    if ok(h.rate_hz) {
        return Ok(exact(h.rate_hz));
    }
    match params.number("POINT", "RATE", false) {
        Some(r) if ok(r as f32) => Ok(exact(r as f32)),
        _ => Err(C3dError::BadRate(h.rate_hz)),
    }
}

/// First frame and frame count, and a POINT:FRAMES (or LONG_FRAMES) disagreement. The header's
/// range wins: the caller checks the data holds it (some writers store POINT:FRAMES one too
/// high). The header's 16-bit last frame saturates at 65535; writers then store the real range
/// in TRIAL:ACTUAL_START_FIELD / ACTUAL_END_FIELD as (low, high) words. A first frame past
/// 65535 cannot be in the header at all: emoshift then stores the take numbered from 1 and its
/// true first frame in EMOSHIFT:FIRST_FRAME, applied here.
fn frame_range(h: &Header, params: &Params) -> Result<(i64, usize, Option<C3dError>), C3dError> {
    let field = |group: &str, name: &str| -> Option<i64> {
        let v = params.numbers(group, name, true)?;
        (v.len() == 2).then(|| v[0] as i64 + ((v[1] as i64) << 16))
    };
    let (mut first, mut last) = (i64::from(h.first_frame), i64::from(h.last_frame));
    if h.last_frame == u16::MAX {
        if let (Some(s), Some(e)) = (
            field("TRIAL", "ACTUAL_START_FIELD"),
            field("TRIAL", "ACTUAL_END_FIELD"),
        ) {
            (first, last) = (s, e);
        }
    }
    if last < first {
        return Err(C3dError::BadFrameRange { first, last });
    }
    let header = (last - first + 1) as usize;
    let parameter = if header > usize::from(u16::MAX) {
        params.number("POINT", "LONG_FRAMES", false)
    } else {
        params.number("POINT", "FRAMES", true)
    };
    let warning = match parameter {
        Some(n) if n as usize != header => Some(C3dError::FrameCountMismatch {
            parameter: n as usize,
            header,
            first,
            last,
        }),
        _ => None,
    };
    let first = field("EMOSHIFT", "FIRST_FRAME").unwrap_or(first);
    Ok((first, header, warning))
}

fn data_block(h: &Header, params: &Params) -> Result<usize, C3dError> {
    let mut block = h.data_block;
    if block < 2 {
        block = params.number("POINT", "DATA_START", true).unwrap_or(0.0) as usize;
    }
    if block < 2 || block == h.parameter_block {
        return Err(C3dError::BadDataStart {
            block,
            parameter_block: h.parameter_block,
        });
    }
    Ok(block)
}

fn units(params: &Params) -> Result<Units, ReadError> {
    let text = params
        .strings("POINT", "UNITS")
        .map(|v| v.concat())
        .unwrap_or_default();
    if text.trim().is_empty() {
        // No units declared (e.g. a header-only file): C3D's customary unit.
        return Ok(Units::Millimetres);
    }
    Units::parse(&text).ok_or(ReadError::UnknownUnits(text))
}

/// POINT:LABELS, continued by LABELS2, LABELS3... for files with more than 255 points; blank or
/// absent labels become `M001`, `M002`..., and repeated labels get a `_2`, `_3`... suffix so
/// every marker stays addressable.
fn labels(params: &Params, points: usize) -> Vec<String> {
    let mut raw = params.strings("POINT", "LABELS").unwrap_or_default();
    let mut k = 2;
    while raw.len() < points {
        match params.strings("POINT", &format!("LABELS{k}")) {
            Some(more) if !more.is_empty() => raw.extend(more),
            _ => break,
        }
        k += 1;
    }
    unique_labels(&raw, points)
}

/// `points` labels from `raw`: a missing or empty one is `M` and its 1-based number, and a
/// repeated one gets the first free `_2`, `_3`, ... suffix.
fn unique_labels(raw: &[String], points: usize) -> Vec<String> {
    // Hashed, both the labels taken and each base's next suffix: a damaged file may repeat one
    // label over 65,535 points, and a linear search per suffix made that cubic (seconds per
    // file; found by fuzzing).
    let mut taken = std::collections::HashSet::with_capacity(points);
    let mut next_suffix = std::collections::HashMap::<String, usize>::new();
    let mut out: Vec<String> = Vec::with_capacity(points);
    for i in 0..points {
        let base = match raw.get(i) {
            Some(l) if !l.is_empty() => l.clone(),
            _ => format!("M{:03}", i + 1),
        };
        let mut label = base.clone();
        if taken.contains(&label) {
            // Every suffix below the one kept for this base was taken, and stays taken.
            let n = next_suffix.entry(base.clone()).or_insert(2);
            while taken.contains(&label) {
                label = format!("{base}_{n}");
                *n += 1;
            }
        }
        taken.insert(label.clone());
        out.push(label);
    }
    out
}

#[cfg(test)]
mod tests;
