//! The 3D samples: decoded by c3dio where it can, by our own decoder otherwise, and the missing
//! mask from the raw residual words either way.

use std::cell::Cell;
use std::panic::{catch_unwind, AssertUnwindSafe};

use c3dio::C3d;

use super::binary::{take2, take4, Header, Processor, BLOCK};
use super::layout::Layout;

/// Which decoder produced the sample values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Decoder {
    /// The c3dio crate.
    C3dio,
    /// emoshift's own decoder, used when c3dio refuses, panics or returns the wrong shape.
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

/// Decodes every sample with our own decoder. The layout has already checked the length.
pub fn own(bytes: &[u8], l: &Layout) -> Samples {
    let n = l.frames * l.points;
    let mut s = Samples {
        xyz: Vec::with_capacity(n * 3),
        invalid: Vec::with_capacity(n),
    };
    for f in 0..l.frames {
        let start = l.data_offset + f * l.frame_bytes();
        let frame = bytes.get(start..).unwrap_or(&[]);
        frame_into(frame, l, &mut s.xyz, &mut s.invalid);
    }
    s
}

/// Decodes one frame record (points then analog samples; only the points are read) and appends
/// its xyz (file units) and residual signs: the one per-frame decoder of both the whole-file
/// and the frame-block readers. Bytes past the end of `frame` read as an invalid zero sample.
pub fn frame_into(frame: &[u8], l: &Layout, xyz: &mut Vec<f32>, invalid: &mut Vec<bool>) {
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

/// Decodes through c3dio: `Ok` with the values when c3dio reads the file with the expected shape,
/// `Err` with c3dio's complaint otherwise (a panic inside c3dio included). Residual signs are not
/// taken from c3dio: it reads the residual byte as signed, which flags large valid residuals as
/// invalid, so the caller keeps the raw words' signs.
pub fn via_c3dio(bytes: &[u8], l: &Layout, h: &Header) -> Result<Vec<f32>, String> {
    // c3dio allocates a grid of the header's frame range x points before reading any data; an
    // out-of-memory abort cannot be caught, so a range the file cannot hold never reaches it.
    let header_frames = usize::from(h.last_frame.saturating_sub(h.first_frame)) + 1;
    if header_frames.saturating_mul(l.points) > bytes.len() / 8 {
        return Err(format!(
            "header frame range {}..{} is too large for c3dio",
            h.first_frame, h.last_frame
        ));
    }
    let param_block = h.parameter_block;
    let canonical = canonical_layout(bytes, l, param_block)?;
    CATCHING.with(|c| c.set(true));
    let parsed = catch_unwind(AssertUnwindSafe(|| {
        C3d::from_bytes(&canonical).map_err(|e| format!("{e:?}"))
    }));
    CATCHING.with(|c| c.set(false));
    let parsed = parsed.map_err(|_| "c3dio panicked".to_string())??;
    let pts = &parsed.points;
    if pts.cols() != l.points || pts.rows() != l.frames {
        return Err(format!(
            "c3dio read {} points x {} frames, expected {} x {}",
            pts.cols(),
            pts.rows(),
            l.points,
            l.frames
        ));
    }
    let mut xyz = Vec::with_capacity(l.points * l.frames * 3);
    for f in 0..l.frames {
        for m in 0..l.points {
            xyz.extend_from_slice(&pts[f][m].point);
        }
    }
    Ok(xyz)
}

/// Checks c3dio's values against our own decoding of the same bytes, over valid samples: a
/// difference beyond float rounding means one of the two misread the layout, and ours is the one
/// whose every step is checked against the header.
pub fn agree(c3dio: &[f32], own: &Samples, l: &Layout) -> Result<(), String> {
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
                    i / l.points,
                    i % l.points
                ));
            }
        }
    }
    Ok(())
}

/// c3dio assumes the parameters start at block 2 and run to the data; files that moved them
/// elsewhere (legal: the header points at both) are rebuilt as header, parameters, data.
fn canonical_layout(bytes: &[u8], l: &Layout, param_block: usize) -> Result<Vec<u8>, String> {
    let p_start = (param_block - 1) * BLOCK;
    let declared = usize::from(bytes[p_start + 2]).max(1);
    let p_end = (p_start + declared * BLOCK).min(bytes.len());
    let data_end = l.data_offset + l.frames * l.frame_bytes();
    let params = bytes
        .get(p_start..p_end)
        .ok_or("parameter blocks outside the file")?;
    let data = bytes.get(l.data_offset..).ok_or("data outside the file")?;
    if data_end > bytes.len() {
        return Err("data outside the file".into());
    }
    let blocks = params.len().div_ceil(BLOCK);
    let data_block = u16::try_from(2 + blocks).map_err(|_| "too many parameter blocks")?;
    let mut out = Vec::with_capacity(BLOCK * (1 + blocks) + data.len());
    out.extend_from_slice(&bytes[..BLOCK]);
    out[0] = 2;
    let word = match l.processor {
        Processor::Mips => data_block.to_be_bytes(),
        Processor::Intel | Processor::Dec => data_block.to_le_bytes(),
    };
    out[16..18].copy_from_slice(&word);
    out.extend_from_slice(params);
    out.resize(BLOCK * (1 + blocks), 0);
    out.extend_from_slice(data);
    Ok(out)
}
