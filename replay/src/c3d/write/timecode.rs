//! The TIMECODE group of a recording's C3D file (issue 16), Vicon's convention.

use super::records::Records;

/// Group id.
const TIMECODE: i8 = 5;

/// The TIMECODE group as Vicon writes it (read by e.g. mocap.ca's translators): USED, DROP_FRAMES,
/// STANDARD (NTSC, PAL or FILM by nominal rate), SUBFRAMESPERFRAME (capture frames per
/// timecode frame), OFFSETS (the first frame's subframe), TIMECODES (hh mm ss ff of the first
/// frame); and RATE, the exact timecode rate, which STANDARD cannot say (29.97, 59.94).
pub(super) fn group(w: &mut Records, tc: &protocol::Smpte, rate_hz: f64) {
    let fps = tc.rate.map_or(0.0, |r| r.fps());
    let nominal = tc.rate.map_or(0, |r| r.nominal_fps());
    w.group(TIMECODE, "TIMECODE", "SMPTE timecode of the first frame");
    w.int(TIMECODE, "USED", &[1]);
    w.byte(
        TIMECODE,
        "DROP_FRAMES",
        u8::from(tc.rate.is_some_and(|r| r.drop_frame())),
    );
    let standard = match nominal {
        30 | 60 => "NTSC".to_string(),
        25 | 50 => "PAL".to_string(),
        24 => "FILM".to_string(),
        n => n.to_string(),
    };
    w.chars(TIMECODE, "STANDARD", &[standard]);
    let per_frame = if fps > 0.0 {
        (rate_hz / fps).round().max(1.0)
    } else {
        1.0
    };
    w.int_dims(TIMECODE, "SUBFRAMESPERFRAME", &[1, 1], &[per_frame as u16]);
    w.int_dims(
        TIMECODE,
        "OFFSETS",
        &[1, 1],
        &[tc.subframe.min(u32::from(u16::MAX)) as u16],
    );
    let hmsf = [tc.hours, tc.minutes, tc.seconds, tc.frames].map(u16::from);
    w.int_dims(TIMECODE, "TIMECODES", &[4, 1], &hmsf);
    w.float(TIMECODE, "RATE", &[fps as f32]);
}

impl Records {
    /// 16-bit integers with explicit dimensions (Vicon's TIMECODE group stores even single
    /// values as 1 x 1 arrays).
    pub(super) fn int_dims(&mut self, group: i8, name: &str, dims: &[u8], values: &[u16]) {
        let data: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.param(group, name, 2, dims, &data);
    }

    pub(super) fn byte(&mut self, group: i8, name: &str, value: u8) {
        self.param(group, name, 1, &[], &[value]);
    }
}
