//! The TRC header of a recording: counts and camera rate as blank-padded placeholders that
//! the file's thread patches in place as frames reach the disk, and the first frame's timecode.

use std::fmt::Write as _;

pub(crate) use crate::durable::{COUNT_WIDTH, RATE_WIDTH};

/// Writes the TRC header with blank-padded frame counts and camera rate into `text`, and a
/// `Timecode` field (the first frame's, `hh:mm:ss:ff.s`, `;` before the frames for drop-frame:
/// readers find fields by name) when there is one; returns the byte offsets of the two counts
/// and of the camera rate.
pub(super) fn trc_header(
    text: &mut String,
    labels: &[String],
    (rate, first): (f64, i64),
    timecode: Option<&protocol::Smpte>,
) -> [u64; 3] {
    let n = labels.len();
    let blank = format!("{:<COUNT_WIDTH$}", 0);
    text.push_str("PathFileType\t4\t(X/Y/Z)\ttake.trc\n");
    text.push_str("DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames");
    text.push_str(if timecode.is_some() {
        "\tTimecode\n"
    } else {
        "\n"
    });
    write!(text, "{rate}\t").expect("String write");
    let camera_rate = text.len() as u64;
    write!(text, "{:<RATE_WIDTH$}\t", format!("{rate}")).expect("String write");
    let num_frames = text.len() as u64;
    write!(text, "{blank}\t{n}\tmm\t{rate}\t{first}\t").expect("String write");
    let orig_num_frames = text.len() as u64;
    write!(text, "{blank}").expect("String write");
    if let Some(tc) = timecode {
        write!(text, "\t{tc}").expect("String write");
    }
    text.push('\n');
    text.push_str("Frame#\tTime");
    for label in labels {
        write!(text, "\t{label}\t\t").expect("String write");
    }
    text.push_str("\n\t");
    for k in 1..=n {
        write!(text, "\tX{k}\tY{k}\tZ{k}").expect("String write");
    }
    text.push_str("\n\n");
    [num_frames, orig_num_frames, camera_rate]
}
