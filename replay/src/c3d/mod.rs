//! C3D takes: decoded once by emoshift's own decoder, cross-checked against the `c3dio` crate
//! on a sample of frames, written by our own Intel float32 writer.
//!
//! Reading checks what c3dio does not: the header's frame range against POINT:FRAMES and the
//! file length, POINT:USED against the header, the units (m and cm become mm). A sample is
//! missing when its xyz is exactly (0, 0, 0) or its residual word is negative; the sign is taken
//! from the raw word because c3dio reads the residual byte as signed. c3dio reads a copy of the
//! file holding up to 256 frames spread evenly over the take, first and last included; its values
//! must agree with ours there. When c3dio refuses a file (e.g. ANALOG:OFFSET stored as float),
//! panics, sees no points (a header-only file with an empty parameter section) or disagrees, the
//! take is still our decoding, and [`C3dInfo`] says why c3dio did not confirm it. Labels come
//! from the parameters, generated as `M001`, `M002`... where none are stored.
//!
//! Writing produces what strict readers (ezc3d, py-c3d) accept: see [`write()`].

mod binary;
mod decode;
pub(crate) mod extent;
mod frames;
mod layout;
mod params;
pub(crate) mod write;

use std::io::Read;

pub use crate::error::c3d::{C3dError, C3dLimitError};
pub use binary::Processor;
pub use decode::{catching_c3dio_panic, Decoder};
pub use frames::C3dBlocks;
pub use write::write;

use crate::error::ReadError;
use crate::Take;

/// What [`read_with_info`] learned about a file besides the take itself.
#[derive(Debug, Clone, PartialEq)]
pub struct C3dInfo {
    /// The processor type the file was written on.
    pub processor: Processor,
    /// Whether points were stored as float32 (otherwise scaled int16).
    pub float: bool,
    /// Whether c3dio confirmed the values on a sample of frames.
    pub decoder: Decoder,
    /// Why c3dio did not confirm them, when it did not.
    pub c3dio_error: Option<String>,
    /// Inconsistencies the file has but that did not stop reading.
    pub warnings: Vec<C3dError>,
}

/// Reads a C3D take.
///
/// # Errors
/// [`ReadError::Io`] when the input fails, [`ReadError::C3d`] naming what is wrong with the file,
/// [`ReadError::UnknownUnits`] for units other than mm, cm or m.
pub fn read(mut input: impl Read) -> Result<Take, ReadError> {
    let mut bytes = Vec::new();
    input.read_to_end(&mut bytes)?;
    read_with_info(&bytes).map(|(take, _)| take)
}

/// The timecode and camera rate a C3D file stores: the first frame's timecode from Vicon's
/// TIMECODE group (its exact rate from `TIMECODE:RATE` when emoshift wrote it, else from
/// STANDARD and DROP_FRAMES), and `TRIAL:CAMERA_RATE`. `None` fields where the file has none.
///
/// # Errors
/// As [`read`], for the header and parameter section.
pub fn read_time(bytes: &[u8]) -> Result<crate::take::RecordTime, ReadError> {
    let (processor, header) = binary::parse_header(bytes)?;
    let params = params::parse(bytes, header.parameter_block, header.data_block, processor)?;
    let camera_rate_hz = params.number("TRIAL", "CAMERA_RATE", false);
    let used = params.number("TIMECODE", "USED", false).unwrap_or(0.0) >= 1.0;
    let hmsf = params
        .numbers("TIMECODE", "TIMECODES", false)
        .filter(|v| v.len() == 4);
    let timecode = match (used, hmsf) {
        (true, Some(v)) => {
            let drop_frame = params.number("TIMECODE", "DROP_FRAMES", false) == Some(1.0);
            let fps = params
                .number("TIMECODE", "RATE", false)
                .filter(|r| *r > 0.0)
                .or_else(|| {
                    let standard = params.strings("TIMECODE", "STANDARD")?;
                    match standard.first()?.as_str() {
                        "NTSC" if drop_frame => Some(29.97),
                        "NTSC" => Some(30.0),
                        "PAL" => Some(25.0),
                        "FILM" => Some(24.0),
                        other => other.parse().ok(),
                    }
                });
            let rate = fps.and_then(|f| {
                let text = format!("{f:.3}{}", if drop_frame { "df" } else { "" });
                protocol::TimecodeRate::parse(&text).ok()
            });
            let sub = params.number("TIMECODE", "OFFSETS", false).unwrap_or(0.0);
            Some(protocol::Smpte {
                hours: v[0] as u8,
                minutes: v[1] as u8,
                seconds: v[2] as u8,
                frames: v[3] as u8,
                subframe: sub as u32,
                rate,
            })
        }
        _ => None,
    };
    Ok(crate::take::RecordTime {
        timecode,
        camera_rate_hz,
    })
}

/// Analog samples per 3D frame, all channels together, from the first bytes of a C3D file
/// (through the parameter section's first block): what emoshift does not read.
///
/// # Errors
/// Bytes that are not the start of a C3D file (see [`read`]).
pub fn analog_per_frame(head: &[u8]) -> Result<usize, C3dError> {
    binary::parse_header(head).map(|(_, h)| usize::from(h.analog_per_frame))
}

/// Reads a C3D take from bytes and reports how it was decoded.
///
/// # Errors
/// As [`read`].
pub fn read_with_info(bytes: &[u8]) -> Result<(Take, C3dInfo), ReadError> {
    let (processor, header, layout) = parse_layout(bytes)?;
    let sample = decode::checked_frames(layout.frames);
    let own = decode::own(bytes, &layout, sample.iter().copied());
    let (decoder, c3dio_error) = match decode::via_c3dio(bytes, &layout, &header, &sample)
        .and_then(|xyz| decode::agree(&xyz, &own, &layout, &sample))
    {
        Ok(()) => (Decoder::C3dio, None),
        Err(e) => (Decoder::Fallback, Some(e)),
    };
    let take = decode_take(bytes, &layout);
    take.validate()?;
    let info = C3dInfo {
        processor,
        float: layout.float,
        decoder,
        c3dio_error,
        warnings: layout.warnings,
    };
    Ok((take, info))
}

/// Reads a C3D take with emoshift's own decoder alone, as the frame-block reader
/// ([`C3dBlocks`]) does: the take [`read`] gives, without its c3dio cross-check on a sample of
/// frames. For the passes that read every take of a long session.
///
/// # Errors
/// As [`read`].
pub fn read_own(mut input: impl Read) -> Result<Take, ReadError> {
    let mut bytes = Vec::new();
    input.read_to_end(&mut bytes)?;
    let (_, _, layout) = parse_layout(&bytes)?;
    let take = decode_take(&bytes, &layout);
    take.validate()?;
    Ok(take)
}

/// The header, then the parameters, then where and how the points are stored.
fn parse_layout(bytes: &[u8]) -> Result<(Processor, binary::Header, layout::Layout), ReadError> {
    let (processor, header) = binary::parse_header(bytes)?;
    let params = params::parse(bytes, header.parameter_block, header.data_block, processor)?;
    let layout = layout::Layout::new(processor, &header, &params, bytes.len())?;
    Ok((processor, header, layout))
}

/// Decodes every frame into a take: millimetres, the missing rule applied ([`push_samples`]).
/// Frames go through a small buffer that stays in cache, so the file's bytes are read once and
/// the take written once.
fn decode_take(bytes: &[u8], l: &layout::Layout) -> Take {
    /// Frames decoded per trip through the buffer.
    const CHUNK: usize = 64;
    let mut take = Take::new(l.labels.clone(), l.rate_hz, l.first_frame);
    take.source_units = l.units;
    take.positions.reserve_exact(l.frames * l.points * 3);
    take.missing.reserve_exact(l.frames * l.points);
    let mut xyz = Vec::with_capacity(CHUNK * l.points * 3);
    let mut invalid = Vec::with_capacity(CHUNK * l.points);
    for start in (0..l.frames).step_by(CHUNK) {
        xyz.clear();
        invalid.clear();
        for f in start..(start + CHUNK).min(l.frames) {
            decode::frame_into(decode::record(bytes, l, f), l, &mut xyz, &mut invalid);
        }
        push_samples(l, &xyz, &invalid, &mut take);
    }
    take
}

/// Appends raw samples (file units) to `take` in millimetres, applying the missing rule: xyz
/// exactly (0, 0, 0), a negative residual word, or a value that is not finite. Shared by the
/// whole-file and frame-block readers so both give the same take.
fn push_samples(l: &layout::Layout, xyz: &[f32], invalid: &[bool], take: &mut Take) {
    let to_mm = l.units.to_mm();
    let (p0, m0) = (take.positions.len(), take.missing.len());
    take.positions.resize(p0 + invalid.len() * 3, 0.0);
    take.missing.resize(m0 + invalid.len(), false);
    let out = take.positions[p0..]
        .chunks_exact_mut(3)
        .zip(&mut take.missing[m0..]);
    // Branch-free: the compiler selects instead of jumping per sample.
    for ((o, gone), (p, &bad)) in out.zip(xyz.chunks_exact(3).zip(invalid)) {
        let finite = p[0].is_finite() & p[1].is_finite() & p[2].is_finite();
        let zero = (p[0] == 0.0) & (p[1] == 0.0) & (p[2] == 0.0);
        let g = bad | zero | !finite;
        *gone = g;
        for (o, v) in o.iter_mut().zip(p) {
            *o = if g { 0.0 } else { v * to_mm };
        }
    }
}
