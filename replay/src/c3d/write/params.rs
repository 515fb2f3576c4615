//! The parameter section: the groups and records strict readers (ezc3d, py-c3d) require, each
//! record chained to the next by its offset word.

use super::{timecode, FrameRange, Meta, INTEL, LABELS_PER_PARAM, SCALE};
use crate::c3d::binary::SIGNATURE;

/// Group ids.
const POINT: i8 = 1;
const ANALOG: i8 = 2;
const FORCE_PLATFORM: i8 = 3;
const TRIAL: i8 = 4;

pub(super) fn parameters(meta: &Meta<'_>, range: &FrameRange, data_block: u16) -> Vec<u8> {
    let mut w = Records::default();
    w.buf.extend_from_slice(&[1, SIGNATURE, 0, INTEL]);
    w.group(POINT, "POINT", "3-D point parameters");
    w.int(POINT, "USED", &[meta.labels.len() as u16]);
    w.int(POINT, "FRAMES", &[range.point_frames()]);
    if range.long() {
        w.float(POINT, "LONG_FRAMES", &[range.count as f32]);
    }
    w.int(POINT, "DATA_START", &[data_block]);
    w.float(POINT, "SCALE", &[SCALE]);
    w.float(POINT, "RATE", &[meta.rate_hz as f32]);
    w.chars(POINT, "UNITS", &["mm".to_string()]);
    let blanks = vec![String::new(); meta.labels.len()];
    for (k, chunk) in meta.labels.chunks(LABELS_PER_PARAM).enumerate() {
        let suffix = if k == 0 {
            String::new()
        } else {
            (k + 1).to_string()
        };
        w.chars(POINT, &format!("LABELS{suffix}"), chunk);
        let descriptions = &blanks[k * LABELS_PER_PARAM..k * LABELS_PER_PARAM + chunk.len()];
        w.chars(POINT, &format!("DESCRIPTIONS{suffix}"), descriptions);
    }
    w.group(ANALOG, "ANALOG", "analog data parameters");
    w.int(ANALOG, "USED", &[0]);
    w.float(ANALOG, "RATE", &[meta.rate_hz as f32]);
    w.float(ANALOG, "GEN_SCALE", &[1.0]);
    w.chars(ANALOG, "FORMAT", &["SIGNED".to_string()]);
    w.int(ANALOG, "BITS", &[16]);
    w.group(
        FORCE_PLATFORM,
        "FORCE_PLATFORM",
        "force platform parameters",
    );
    w.int(FORCE_PLATFORM, "USED", &[0]);
    w.group(TRIAL, "TRIAL", "trial parameters");
    let words = |v: u32| [(v & 0xFFFF) as u16, (v >> 16) as u16];
    w.int(TRIAL, "ACTUAL_START_FIELD", &words(range.first));
    w.int(TRIAL, "ACTUAL_END_FIELD", &words(range.last));
    if let Some(rate) = meta.time.and_then(|t| t.camera_rate_hz) {
        w.float(TRIAL, "CAMERA_RATE", &[rate as f32]);
    }
    if let Some(tc) = meta.time.and_then(|t| t.timecode) {
        timecode::group(&mut w, &tc, meta.rate_hz);
    }
    w.finish()
}

/// Builds group and parameter records; each record's "offset to next" is patched when the next
/// one starts, and the last stays 0, which ends the section.
#[derive(Default)]
pub(super) struct Records {
    pub(super) buf: Vec<u8>,
    /// Position of the previous record's offset word.
    pub(super) pending: Option<usize>,
}

impl Records {
    pub(super) fn start(&mut self, id: i8, name: &str) {
        let here = self.buf.len();
        if let Some(at) = self.pending {
            let offset = (here - at) as u16;
            self.buf[at..at + 2].copy_from_slice(&offset.to_le_bytes());
        }
        self.buf.push(name.len() as u8);
        self.buf.push(id as u8);
        self.buf.extend_from_slice(name.as_bytes());
        self.pending = Some(self.buf.len());
        self.buf.extend_from_slice(&[0, 0]);
    }

    pub(super) fn group(&mut self, id: i8, name: &str, description: &str) {
        self.start(-id, name);
        self.buf.push(description.len() as u8);
        self.buf.extend_from_slice(description.as_bytes());
    }

    pub(super) fn param(&mut self, group: i8, name: &str, ty: i8, dims: &[u8], data: &[u8]) {
        self.start(group, name);
        self.buf.push(ty as u8);
        self.buf.push(dims.len() as u8);
        self.buf.extend_from_slice(dims);
        self.buf.extend_from_slice(data);
        self.buf.push(0); // no description
    }

    pub(super) fn int(&mut self, group: i8, name: &str, values: &[u16]) {
        let data: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.param(group, name, 2, &number_dims(values.len()), &data);
    }

    pub(super) fn float(&mut self, group: i8, name: &str, values: &[f32]) {
        let data: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.param(group, name, 4, &number_dims(values.len()), &data);
    }

    /// A character array of `strings.len()` strings, blank-padded to the longest (at least 1:
    /// a zero dimension upsets some readers). Callers keep strings within 255 bytes.
    pub(super) fn chars(&mut self, group: i8, name: &str, strings: &[String]) {
        let width = strings.iter().map(String::len).max().unwrap_or(0).max(1);
        let mut data = Vec::with_capacity(width * strings.len());
        for s in strings {
            data.extend_from_slice(s.as_bytes());
            data.resize(data.len() + width - s.len(), b' ');
        }
        let dims = if strings.len() == 1 {
            vec![width as u8]
        } else {
            vec![width as u8, strings.len() as u8]
        };
        self.param(group, name, -1, &dims, &data);
    }

    pub(super) fn finish(self) -> Vec<u8> {
        self.buf
    }
}

/// Dimensions of a numeric parameter of `count` values: none for a scalar, else one
/// (callers write a few values at most).
fn number_dims(count: usize) -> Vec<u8> {
    if count == 1 {
        vec![]
    } else {
        vec![count as u8]
    }
}
