//! The 3D samples: decoded by our own decoder, cross-checked by c3dio on a sample of frames,
//! and the missing mask from the raw residual words.

use std::cell::Cell;
use std::panic::{catch_unwind, AssertUnwindSafe};

use c3dio::C3d;

use super::binary::{take2, take4, Header, Processor, BLOCK};
use super::layout::Layout;

/// Who vouches for the sample values, which emoshift's own decoder produces either way.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Decoder {
    /// The c3dio crate read the same values on a sample of frames (up to 256, spread over
    /// the take).
    C3dio,
    /// emoshift's own decoder alone: c3dio refused, panicked, returned the wrong shape or
    /// disagreed.
    Fallback,
}

/// Raw samples in file units: xyz per point per frame, and whether the residual word is negative.
#[derive(Debug, Clone, PartialEq)]
pub struct Samples {
    /// frames x points x 3, file units (int16 values already multiplied by the scale).
    pub xyz: Vec<f32>,
    /// frames x points: the residual word is negative (the C3D "invalid" flag).
    pub invalid: Vec<bool>,
}

/// Decodes the frames at `frames` (0-based indices) with our own decoder, in that order. The
/// layout has already checked the length.
pub fn own(bytes: &[u8], l: &Layout, frames: impl ExactSizeIterator<Item = usize>) -> Samples {
    let n = frames.len() * l.points;
    let mut s = Samples {
        xyz: Vec::with_capacity(n * 3),
        invalid: Vec::with_capacity(n),
    };
    for f in frames {
        frame_into(record(bytes, l, f), l, &mut s.xyz, &mut s.invalid);
    }
    s
}

/// Frame `f`'s record and whatever follows it (empty past the end).
pub fn record<'a>(bytes: &'a [u8], l: &Layout, f: usize) -> &'a [u8] {
    bytes
        .get(l.data_offset + f * l.frame_bytes()..)
        .unwrap_or(&[])
}

/// Decodes one frame record (points then analog samples; only the points are read) and appends
/// its xyz (file units) and residual signs: the one per-frame decoder of both the whole-file
/// and the frame-block readers. Bytes past the end of `frame` read as an invalid zero sample.
pub fn frame_into(frame: &[u8], l: &Layout, xyz: &mut Vec<f32>, invalid: &mut Vec<bool>) {
    // Intel float32, the common case: four little-endian floats per point, read without the
    // per-value checks of the general decoder below (which gives the same values).
    if l.float && l.processor == super::binary::Processor::Intel {
        if let Some(points) = frame.get(..l.points * 16) {
            let (x0, i0) = (xyz.len(), invalid.len());
            xyz.resize(x0 + 3 * l.points, 0.0);
            invalid.resize(i0 + l.points, false);
            let out = xyz[x0..].chunks_exact_mut(3).zip(&mut invalid[i0..]);
            for (p, (o, bad)) in points.chunks_exact(16).zip(out) {
                let v = |k: usize| {
                    f32::from_le_bytes([p[4 * k], p[4 * k + 1], p[4 * k + 2], p[4 * k + 3]])
                };
                o.copy_from_slice(&[v(0), v(1), v(2)]);
                *bad = (v(3) as i32) < 0;
            }
            return;
        }
    }
    let word = l.word();
    for m in 0..l.points {
        let at = m * 4 * word;
        let v = |k: usize| value(frame, at + k * word, l);
        xyz.extend([v(0), v(1), v(2)]);
        invalid.push(residual_word(frame, at + 3 * word, l) < 0);
    }
}

fn value(bytes: &[u8], at: usize, l: &Layout) -> f32 {
    if l.float {
        take4(bytes, at).map_or(0.0, |b| l.processor.f32(b))
    } else {
        take2(bytes, at).map_or(0.0, |b| f32::from(l.processor.i16(b)) * l.scale)
    }
}

/// The fourth word of a point as a signed 16-bit value: (cameras << 8) | residual, negative when
/// the sample is invalid. Float files store the same 16-bit pattern as a float.
fn residual_word(bytes: &[u8], at: usize, l: &Layout) -> i32 {
    if l.float {
        take4(bytes, at).map_or(-1, |b| l.processor.f32(b) as i32)
    } else {
        take2(bytes, at).map_or(-1, |b| i32::from(l.processor.i16(b)))
    }
}

thread_local! {
    static CATCHING: Cell<bool> = const { Cell::new(false) };
}

/// Whether this thread is inside the c3dio call whose panics the C3D reader catches and
/// reports as an error ([`super::C3dInfo::c3dio_error`]): a binary's panic hook can stay quiet
/// for those (the file is then read by emoshift's own decoder alone), and speak for every
/// other.
pub fn catching_c3dio_panic() -> bool {
    CATCHING.with(Cell::get)
}

/// Frames the c3dio cross-check reads: every frame of a take this short, else this many spread
/// evenly from the first frame to the last. A misread layout (a wrong frame length, word size or
/// byte order) shows within the first frames; the spread also covers the file's end.
pub const CHECKED_FRAMES: usize = 256;

/// The frame indices the c3dio cross-check reads out of `frames`, ascending, first and last
/// included.
pub fn checked_frames(frames: usize) -> Vec<usize> {
    if frames <= CHECKED_FRAMES {
        return (0..frames).collect();
    }
    let span = frames - 1;
    (0..CHECKED_FRAMES)
        .map(|k| k * span / (CHECKED_FRAMES - 1))
        .collect()
}

/// Decodes the frames `sample` (indices from [`checked_frames`]) through c3dio: `Ok` with their
/// values (sample x points x 3) when c3dio reads them with the expected shape, `Err` with
/// c3dio's complaint otherwise (a panic inside c3dio included). c3dio parses a copy of the file
/// that holds only those frames' records (and zero padding to a whole block). Residual signs are not taken from c3dio: it reads the
/// residual byte as signed, which flags large valid residuals as invalid.
pub fn via_c3dio(
    bytes: &[u8],
    l: &Layout,
    h: &Header,
    sample: &[usize],
) -> Result<Vec<f32>, String> {
    // c3dio allocates a grid of the header's frame range x points before reading any data; an
    // out-of-memory abort cannot be caught, so a range the file cannot hold never reaches it.
    let header_frames = usize::from(h.last_frame.saturating_sub(h.first_frame)) + 1;
    if header_frames.saturating_mul(l.points) > bytes.len() / 8 {
        return Err(format!(
            "header frame range {}..{} is too large for c3dio",
            h.first_frame, h.last_frame
        ));
    }
    // Likewise its analog grid, frames x ANALOG:USED x samples per channel: parameters that
    // claim more analog samples than a frame's record holds (gigabytes from a 12 KB file,
    // found by fuzzing) never reach it.
    if l.analog_claimed > l.analog_per_frame.max(1) {
        return Err(format!(
            "the parameters claim {} analog samples a frame where the records hold {}, too many \
             for c3dio",
            l.analog_claimed, l.analog_per_frame
        ));
    }
    let canonical = canonical_layout(bytes, l, h, sample)?;
    CATCHING.with(|c| c.set(true));
    let parsed = catch_unwind(AssertUnwindSafe(|| {
        C3d::from_bytes(&canonical).map_err(|e| format!("{e:?}"))
    }));
    CATCHING.with(|c| c.set(false));
    let parsed = parsed.map_err(|_| "c3dio panicked".to_string())??;
    let pts = &parsed.points;
    // The copy's last block is padded with zeros, which c3dio may read as further frames.
    if pts.cols() != l.points || pts.rows() < sample.len() {
        return Err(format!(
            "c3dio read {} points x {} frames, expected {} x {}",
            pts.cols(),
            pts.rows(),
            l.points,
            sample.len()
        ));
    }
    let mut xyz = Vec::with_capacity(l.points * sample.len() * 3);
    for f in 0..sample.len() {
        for m in 0..l.points {
            xyz.extend_from_slice(&pts[f][m].point);
        }
    }
    Ok(xyz)
}

/// Checks c3dio's values of the frames `sample` against our own decoding of the same frames
/// (`own`, in the same order), over valid samples: a difference beyond float rounding means one
/// of the two misread the layout, and ours is the one whose every step is checked against the
/// header.
pub fn agree(c3dio: &[f32], own: &Samples, l: &Layout, sample: &[usize]) -> Result<(), String> {
    for (i, &bad) in own.invalid.iter().enumerate() {
        if bad {
            continue;
        }
        let pairs = c3dio[i * 3..i * 3 + 3]
            .iter()
            .zip(&own.xyz[i * 3..i * 3 + 3]);
        for (&a, &b) in pairs {
            let both_nan = a.is_nan() && b.is_nan();
            if !both_nan && (a - b).abs() > 1e-4 * b.abs().max(1.0) {
                return Err(format!(
                    "c3dio reads {a} where the raw data holds {b} (frame index {}, point {})",
                    sample[i / l.points],
                    i % l.points
                ));
            }
        }
    }
    Ok(())
}

/// c3dio assumes the parameters start at block 2 and run to the data; files that moved them
/// elsewhere (legal: the header points at both) are rebuilt as header, parameters, data. The
/// copy holds only the records of the frames `sample`, and its header's frame range says so.
fn canonical_layout(
    bytes: &[u8],
    l: &Layout,
    h: &Header,
    sample: &[usize],
) -> Result<Vec<u8>, String> {
    let p_start = (h.parameter_block - 1) * BLOCK;
    let declared = usize::from(bytes[p_start + 2]).max(1);
    let p_end = (p_start + declared * BLOCK).min(bytes.len());
    let record = l.frame_bytes();
    let data_end = l.data_offset + l.frames * record;
    let params = bytes
        .get(p_start..p_end)
        .ok_or("parameter blocks outside the file")?;
    if data_end > bytes.len() {
        return Err("data outside the file".into());
    }
    c3dio_walk_ends(params, l.processor)?;
    let blocks = params.len().div_ceil(BLOCK);
    let data_block = u16::try_from(2 + blocks).map_err(|_| "too many parameter blocks")?;
    let mut out = Vec::with_capacity(BLOCK * (1 + blocks) + sample.len() * record);
    out.extend_from_slice(&bytes[..BLOCK]);
    out[0] = 2;
    let last = u16::try_from(sample.len().saturating_sub(1))
        .map_or(u16::MAX, |k| h.first_frame.saturating_add(k));
    let word = |v: u16| match l.processor {
        Processor::Mips => v.to_be_bytes(),
        Processor::Intel | Processor::Dec => v.to_le_bytes(),
    };
    out[8..10].copy_from_slice(&word(last));
    out[16..18].copy_from_slice(&word(data_block));
    out.extend_from_slice(params);
    out.resize(BLOCK * (1 + blocks), 0);
    for &f in sample {
        let at = l.data_offset + f * record;
        out.extend_from_slice(&bytes[at..at + record]);
    }
    // c3dio wants whole blocks.
    out.resize(out.len().next_multiple_of(BLOCK), 0);
    Ok(out)
}

/// Whether c3dio 0.8's walk over the parameter records `params` (the section from its first
/// byte) reaches an end. It steps from record to record by the name's length and the "next"
/// offset after it, taking the length byte as `i8` and its absolute value: a length byte of
/// 0x80 (-128) overflows and sends the walk backwards, into a loop that allocates without bound
/// (found by fuzzing: gigabytes from a 12 KB file). Every other record moves it forward, so a
/// section without that byte on the walk's path ends, as here.
pub(crate) fn c3dio_walk_ends(params: &[u8], processor: Processor) -> Result<(), String> {
    let mut at = 4;
    // c3dio stops at a group id of zero, or at the section's end.
    while at + 1 < params.len() && params[at + 1] != 0 {
        let name_len = i8::from_ne_bytes([params[at]]);
        if name_len == i8::MIN {
            return Err(format!(
                "a parameter name length of -128 at byte {at} of the parameters, which c3dio \
                 cannot step past"
            ));
        }
        let offset_at = at + 2 + usize::from(name_len.unsigned_abs());
        // Past the end, c3dio's own slice fails (an error or a caught panic): it ends there.
        let Some(offset) = take2(params, offset_at) else {
            return Ok(());
        };
        at = offset_at + usize::from(processor.u16(offset));
    }
    Ok(())
}

#[cfg(test)]
mod tests;
