//! NAT_FRAMEOFDATA encoder, for emoshift's Motive stand-in (tests, bench, loopback demo).

use super::error::NatNetEncodeError;
use super::frame::{AnalogData, FrameOfData, LabeledMarker, RigidBody};
use super::message::{begin_packet, finish_packet, MessageId};
use super::version::NatNetVersion;
use super::wire::{
    begin_size, end_size, put_count, put_cstr, put_f32, put_f32s, put_i32, put_u16, put_u32,
    put_u64,
};

type Enc = Result<(), NatNetEncodeError>;

/// Encodes `frame` as a NAT_FRAMEOFDATA of NatNet `version` into `out` (cleared first).
///
/// Every section is written, with NatNet 4.1's section sizes when the version has them.
/// Assets are not represented in [`FrameOfData`]: 4.1 frames carry an empty asset section.
/// The precision timestamp is written for 4.1+ (zero when `None`) and for 4.0 when `Some`.
/// Allocates only if `out` is too small.
///
/// # Errors
///
/// [`NatNetEncodeError::UnsupportedVersion`] outside 3.x–4.x; a markerset name with a NUL;
/// a payload over 65,535 bytes.
pub fn encode_frame_into(frame: &FrameOfData, version: NatNetVersion, out: &mut Vec<u8>) -> Enc {
    if !version.is_supported() {
        return Err(NatNetEncodeError::UnsupportedVersion {
            major: version.major,
            minor: version.minor,
        });
    }
    let v = version;
    begin_packet(out, MessageId::FrameOfData);
    put_i32(out, frame.frame_number);
    section(out, v, frame.markerset_count(), |out| {
        for m in frame.markersets() {
            put_cstr(out, m.name)?;
            put_count(out, m.positions.len())?;
            m.positions.iter().for_each(|p| put_f32s(out, p));
        }
        Ok(())
    })?;
    section(out, v, frame.other_markers.len(), |out| {
        frame.other_markers.iter().for_each(|p| put_f32s(out, p));
        Ok(())
    })?;
    section(out, v, frame.rigid_bodies.len(), |out| {
        frame
            .rigid_bodies
            .iter()
            .for_each(|b| put_rigid_body(out, b));
        Ok(())
    })?;
    section(out, v, frame.skeleton_count(), |out| {
        for s in frame.skeletons() {
            put_i32(out, s.id);
            put_count(out, s.bones.len())?;
            s.bones.iter().for_each(|b| put_rigid_body(out, b));
        }
        Ok(())
    })?;
    if v.has_section_sizes() {
        section(out, v, 0, |_| Ok(()))?;
    }
    section(out, v, frame.labeled_markers.len(), |out| {
        frame
            .labeled_markers
            .iter()
            .for_each(|m| put_labeled_marker(out, m));
        Ok(())
    })?;
    put_analog(out, v, &frame.force_plates)?;
    put_analog(out, v, &frame.devices)?;
    put_suffix(out, v, frame);
    finish_packet(out)
}

/// Count, then (4.1+) the byte size of what `body` writes, then the body.
fn section(
    out: &mut Vec<u8>,
    v: NatNetVersion,
    n: usize,
    body: impl FnOnce(&mut Vec<u8>) -> Enc,
) -> Enc {
    put_count(out, n)?;
    if !v.has_section_sizes() {
        return body(out);
    }
    let start = begin_size(out);
    body(out)?;
    end_size(out, start)
}

fn put_rigid_body(out: &mut Vec<u8>, b: &RigidBody) {
    put_i32(out, b.id);
    put_f32s(out, &b.position);
    put_f32s(out, &b.orientation);
    put_f32(out, b.mean_error);
    put_u16(out, b.params);
}

fn put_labeled_marker(out: &mut Vec<u8>, m: &LabeledMarker) {
    put_u32(out, m.id);
    put_f32s(out, &m.position);
    put_f32(out, m.size);
    put_u16(out, m.params.0);
    put_f32(out, m.residual);
}

fn put_analog(out: &mut Vec<u8>, v: NatNetVersion, a: &AnalogData) -> Enc {
    section(out, v, a.len(), |out| {
        for i in 0..a.len() {
            put_i32(out, a.id(i).unwrap_or_default());
            let channels = a.channel_count(i);
            put_count(out, channels)?;
            for c in 0..channels {
                let s = a.samples(i, c).unwrap_or_default();
                put_count(out, s.len())?;
                put_f32s(out, s);
            }
        }
        Ok(())
    })
}

fn put_suffix(out: &mut Vec<u8>, v: NatNetVersion, f: &FrameOfData) {
    put_u32(out, f.timecode);
    put_u32(out, f.timecode_subframe);
    out.extend_from_slice(&f.timestamp.to_le_bytes());
    put_u64(out, f.camera_mid_exposure);
    put_u64(out, f.camera_data_received);
    put_u64(out, f.transmit);
    let precision = if v.has_precision_timestamp() {
        Some(f.precision_timestamp.unwrap_or_default())
    } else if v.major == 4 {
        f.precision_timestamp
    } else {
        None
    };
    if let Some(p) = precision {
        put_u32(out, p.seconds);
        put_u32(out, p.fraction);
    }
    put_u16(out, f.params.0);
    put_u32(out, 0);
}
