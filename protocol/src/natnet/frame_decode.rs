//! NAT_FRAMEOFDATA decoder, following the SDK's PacketClient section by section.

use super::error::NatNetError;
use super::frame::{
    FrameOfData, FrameParams, LabeledMarker, MarkerParams, PrecisionTimestamp, RigidBody,
};
use super::message::{expect_packet, MessageId, HEADER_LEN};
use super::version::NatNetVersion;
use super::wire::Reader;

type R<T> = Result<T, NatNetError>;

/// Minimum wire sizes, for rejecting impossible counts before reading.
const MARKERSET_MIN: usize = 1 + 4;
const VEC3: usize = 12;
const RIGID_BODY: usize = 4 + 12 + 16 + 4 + 2;
const SKELETON_MIN: usize = 4 + 4;
const ASSET_MIN: usize = 4 + 4 + 4;
const ASSET_MARKER: usize = 4 + 12 + 4 + 2 + 4;
const LABELED_MARKER: usize = 4 + 12 + 4 + 2 + 4;
const ANALOG_MIN: usize = 4 + 4;
/// Suffix after the three high-resolution stamps: params, end-of-data tag.
const TAIL: usize = 2 + 4;
const PRECISION: usize = 4 + 4;

/// Decodes a NAT_FRAMEOFDATA datagram (header included) of NatNet `version` into `frame`.
///
/// `frame` is cleared first; on error it holds whatever was decoded before the error. Once
/// its lists are large enough this allocates nothing (see `tests/it/natnet_alloc.rs`).
///
/// # Errors
///
/// [`NatNetError::UnsupportedVersion`] for versions other than 3.x and 4.x; framing errors
/// from [`check_packet`](super::check_packet); [`NatNetError::WrongMessage`] for another
/// message; truncation, impossible counts, bad 4.1 section sizes, infinite floats (NaN
/// passes through), a non-finite timestamp, non-UTF-8 names, trailing bytes.
pub fn decode_frame_into(
    datagram: &[u8],
    version: NatNetVersion,
    frame: &mut FrameOfData,
) -> Result<(), NatNetError> {
    version.check()?;
    expect_packet(datagram, MessageId::FrameOfData)?;
    frame.clear();
    let r = &mut Reader::at(datagram, HEADER_LEN);
    frame.frame_number = r.i32()?;
    markersets(r, version, frame)?;
    let n = r.count(VEC3)?;
    sized(r, version, |r| {
        for _ in 0..n {
            frame.other_markers.push(r.vec3()?);
        }
        Ok(())
    })?;
    let n = r.count(RIGID_BODY)?;
    sized(r, version, |r| {
        for _ in 0..n {
            frame.rigid_bodies.push(rigid_body(r)?);
        }
        Ok(())
    })?;
    skeletons(r, version, frame)?;
    if version.has_section_sizes() {
        frame.asset_count = assets(r, version)?;
    }
    let n = r.count(LABELED_MARKER)?;
    sized(r, version, |r| {
        for _ in 0..n {
            frame.labeled_markers.push(labeled_marker(r)?);
        }
        Ok(())
    })?;
    analog(r, version, &mut frame.force_plates)?;
    analog(r, version, &mut frame.devices)?;
    suffix(r, version, frame)?;
    r.finish()
}

/// Runs `body`, bracketed by NatNet 4.1's section size: the size field comes right after the
/// count and must equal the bytes `body` consumed.
fn sized<T>(
    r: &mut Reader<'_>,
    v: NatNetVersion,
    body: impl FnOnce(&mut Reader<'_>) -> R<T>,
) -> R<T> {
    if !v.has_section_sizes() {
        return body(r);
    }
    let offset = r.pos();
    let declared = r.i32()?;
    let start = r.pos();
    let out = body(r)?;
    let actual = r.pos() - start;
    if usize::try_from(declared).ok() != Some(actual) {
        return Err(NatNetError::SectionSize {
            offset,
            declared: usize::try_from(declared).unwrap_or(usize::MAX),
            actual,
        });
    }
    Ok(out)
}

fn markersets(r: &mut Reader<'_>, v: NatNetVersion, frame: &mut FrameOfData) -> R<()> {
    let n = r.count(MARKERSET_MIN)?;
    sized(r, v, |r| {
        for _ in 0..n {
            frame.begin_markerset(r.cstr()?);
            let m = r.count(VEC3)?;
            for _ in 0..m {
                frame.push_markerset_position(r.vec3()?);
            }
        }
        Ok(())
    })
}

fn rigid_body(r: &mut Reader<'_>) -> R<RigidBody> {
    // NatNet 3.0 dropped the per-body marker lists of 2.x (PacketClient: `if (major < 3)`).
    Ok(RigidBody {
        id: r.i32()?,
        position: r.vec3()?,
        orientation: r.quat()?,
        mean_error: r.f32()?,
        params: r.u16()?,
    })
}

fn skeletons(r: &mut Reader<'_>, v: NatNetVersion, frame: &mut FrameOfData) -> R<()> {
    let n = r.count(SKELETON_MIN)?;
    sized(r, v, |r| {
        for _ in 0..n {
            let id = r.i32()?;
            frame.push_skeleton(id, &[]);
            let bones = r.count(RIGID_BODY)?;
            for _ in 0..bones {
                frame.push_skeleton_bone(rigid_body(r)?);
            }
        }
        Ok(())
    })
}

/// NatNet 4.1 assets: id, rigid bodies (id, pose, error, params), markers (id, position,
/// size, params, residual). Checked and skipped.
fn assets(r: &mut Reader<'_>, v: NatNetVersion) -> R<usize> {
    let n = r.count(ASSET_MIN)?;
    sized(r, v, |r| {
        for _ in 0..n {
            r.skip(4)?;
            let bodies = r.count(RIGID_BODY)?;
            for _ in 0..bodies {
                rigid_body(r)?;
            }
            let markers = r.count(ASSET_MARKER)?;
            for _ in 0..markers {
                labeled_marker(r)?;
            }
        }
        Ok(n)
    })
}

fn labeled_marker(r: &mut Reader<'_>) -> R<LabeledMarker> {
    Ok(LabeledMarker {
        id: r.u32()?,
        position: r.vec3()?,
        size: r.f32()?,
        params: MarkerParams(r.u16()?),
        residual: r.f32()?,
    })
}

/// Force plates and devices share a layout: id, channels, per channel its samples.
fn analog(r: &mut Reader<'_>, v: NatNetVersion, out: &mut super::frame::AnalogData) -> R<()> {
    let n = r.count(ANALOG_MIN)?;
    sized(r, v, |r| {
        for _ in 0..n {
            out.begin_device(r.i32()?);
            let channels = r.count(4)?;
            for _ in 0..channels {
                out.begin_channel();
                let samples = r.count(4)?;
                for _ in 0..samples {
                    out.push_sample(r.f32()?);
                }
            }
        }
        Ok(())
    })
}

fn suffix(r: &mut Reader<'_>, v: NatNetVersion, frame: &mut FrameOfData) -> R<()> {
    frame.timecode = r.u32()?;
    frame.timecode_subframe = r.u32()?;
    let at = r.pos();
    let ts = r.f64()?;
    if !ts.is_finite() {
        return Err(NatNetError::NonFinite { offset: at });
    }
    frame.timestamp = ts;
    frame.camera_mid_exposure = r.u64()?;
    frame.camera_data_received = r.u64()?;
    frame.transmit = r.u64()?;
    // 4.1+ always carries the precision timestamp; the SDK disagrees about 4.0 (C++ no,
    // Python yes), so a 4.0 frame is read by its length: the tail is fixed.
    let precision =
        v.has_precision_timestamp() || (v.major == 4 && r.remaining() == PRECISION + TAIL);
    if precision {
        frame.precision_timestamp = Some(PrecisionTimestamp {
            seconds: r.u32()?,
            fraction: r.u32()?,
        });
    }
    frame.params = FrameParams(r.u16()?);
    // End-of-data tag: 0 in every capture; PacketClient reads it without checking.
    r.u32()?;
    Ok(())
}
