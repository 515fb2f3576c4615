//! The parameter section: the groups and records strict readers (ezc3d, py-c3d) require, each
//! record chained to the next by its offset word.

use super::records::Records;
use super::{timecode, FrameRange, Meta, INTEL, LABELS_PER_PARAM, SCALE};
use crate::c3d::binary::SIGNATURE;

/// Group ids.
const POINT: i8 = 1;
const ANALOG: i8 = 2;
const FORCE_PLATFORM: i8 = 3;
const TRIAL: i8 = 4;
const EMOSHIFT: i8 = 5;

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
    if let Some(first) = range.renumbered_from {
        w.group(EMOSHIFT, "EMOSHIFT", "emoshift's additions");
        w.int(EMOSHIFT, "FIRST_FRAME", &words(first));
    }
    w.finish()
}
