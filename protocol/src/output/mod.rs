//! Output profiles: compact, flat-split and components. All encode into a caller `Vec<u8>`
//! (cleared, capacity reused) without other allocation.

mod decode;

pub use decode::{
    decode_blend_val, decode_components_into, decode_part_into, decode_state, decode_stream,
    PartHeader, State,
};

use crate::address::{COMPONENTS, PART, STATE, STREAM, VMC_BLEND_APPLY, VMC_BLEND_VAL};
use crate::error::EncodeError;
use crate::frame::{append_frame, FrameBuf};
use crate::wire::{self, pad4};

/// Payload that fits one Ethernet frame: 1,500 - 20 (IPv4) - 8 (UDP).
pub const ETHERNET_PAYLOAD: usize = 1_472;

/// Longest stream name `/emoshift/stream` carries, bytes.
pub const MAX_STREAM_NAME_BYTES: usize = 64;
/// Bytes the stream's bundle adds to a `/mocap/part` at most: bundle header, the stream
/// message with the longest name, and the part's element size.
const STREAM_OVERHEAD: usize = 16 + 4 + 20 + 4 + 4 + (MAX_STREAM_NAME_BYTES + 4) + 4;

/// Which stream an output belongs to: an id stable for the daemon's session, and the
/// performer's name (or `ip:port/layout` when none is configured).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StreamTag<'a> {
    /// Stream id; also the layout id of the `/mocap/labels` naming its markers.
    pub id: i32,
    /// Its name, at most [`MAX_STREAM_NAME_BYTES`].
    pub name: &'a str,
}

/// Starts an output bundle with `/emoshift/stream ,is`.
fn begin_stream_bundle(tag: &StreamTag<'_>, out: &mut Vec<u8>) -> Result<(), EncodeError> {
    out.clear();
    if tag.name.len() > MAX_STREAM_NAME_BYTES {
        return Err(EncodeError::NameTooLong {
            len: tag.name.len(),
            max: MAX_STREAM_NAME_BYTES,
        });
    }
    wire::put_bundle_header(out);
    let at = wire::begin_element(out);
    wire::put_str_unchecked(out, STREAM);
    wire::put_str_unchecked(out, ",is");
    wire::put_i32(out, tag.id);
    if let Err(e) = wire::put_str(out, tag.name) {
        out.clear();
        return Err(e);
    }
    wire::end_element(out, at);
    Ok(())
}

/// Encodes the compact profile: one bundle (time tag "immediately") holding
/// `/emoshift/stream ,is`, the edited frame as `/mocap/frame ,ihbb` and then
/// `/emoshift/state ,sf` (target emotion, current amount). A bundle keeps them atomic in one
/// datagram: 1,464 bytes for 109 markers, a stream name of up to 7 bytes and a target name of
/// up to 11. Returns the encoded length.
///
/// # Errors
/// [`EncodeError::NonFinite`] for a present marker that is not finite,
/// [`EncodeError::NulInString`] for a NUL in `target` or the stream name,
/// [`EncodeError::NameTooLong`] for a stream name past [`MAX_STREAM_NAME_BYTES`].
pub fn encode_compact_into(
    tag: &StreamTag<'_>,
    frame: &FrameBuf,
    target: &str,
    amount: f32,
    out: &mut Vec<u8>,
) -> Result<usize, EncodeError> {
    begin_stream_bundle(tag, out)?;
    let at = wire::begin_element(out);
    append_frame(frame, out)?;
    wire::end_element(out, at);
    let at = wire::begin_element(out);
    wire::put_str_unchecked(out, STATE);
    wire::put_str_unchecked(out, ",sf");
    if let Err(e) = wire::put_str(out, target) {
        out.clear();
        return Err(e);
    }
    wire::put_f32(out, amount);
    wire::end_element(out, at);
    Ok(out.len())
}

/// How a frame is cut into parts, each one datagram: a bundle of `/emoshift/stream ,is` and
/// `/mocap/part ,iiii f...`: frame number, first marker, markers in this part, markers in the
/// frame, then 3 floats a marker (NaN = missing).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FlatSplit {
    markers_per_part: usize,
}

/// Bytes of a part message with `k` markers.
const fn part_len(k: usize) -> usize {
    12 + pad4(1 + 4 + 3 * k + 1) + 16 + 12 * k
}

impl FlatSplit {
    /// The split whose parts (with their stream bundle) are at most `max_bytes` long
    /// ([`ETHERNET_PAYLOAD`] by default; 4,096 for receivers with 4 KB buffers).
    ///
    /// # Errors
    /// [`EncodeError::PartTooSmall`] if not even one marker fits.
    pub fn new(max_bytes: usize) -> Result<FlatSplit, EncodeError> {
        // part_len grows by 15 bytes a marker (+ padding); search down from an upper bound
        let mut k = max_bytes / 15 + 1;
        while k > 0 && part_len(k) + STREAM_OVERHEAD > max_bytes {
            k -= 1;
        }
        if k == 0 {
            return Err(EncodeError::PartTooSmall { max: max_bytes });
        }
        Ok(FlatSplit {
            markers_per_part: k,
        })
    }

    /// Markers each part carries (the last may carry fewer).
    pub fn markers_per_part(&self) -> usize {
        self.markers_per_part
    }

    /// Parts needed for `markers` markers (at least 1, so that an empty frame is still sent).
    pub fn part_count(&self, markers: usize) -> usize {
        markers.div_ceil(self.markers_per_part).max(1)
    }

    /// Encodes part `part` of `frame` with its stream `tag` into `out` (cleared first).
    /// Returns the encoded length, or 0 if `part` is past the last part.
    ///
    /// # Errors
    /// As the stream tag of [`encode_compact_into`].
    pub fn encode_part_into(
        &self,
        tag: &StreamTag<'_>,
        frame: &FrameBuf,
        part: usize,
        out: &mut Vec<u8>,
    ) -> Result<usize, EncodeError> {
        out.clear();
        let n = frame.marker_count();
        let first = part * self.markers_per_part;
        if part >= self.part_count(n) {
            return Ok(0);
        }
        let count = self.markers_per_part.min(n - first);
        begin_stream_bundle(tag, out)?;
        let at = wire::begin_element(out);
        let start = out.len();
        wire::put_prologue(out, start, PART, b"iiii", b'f', 3 * count);
        let h = frame.header();
        wire::put_i32(out, h.frame_number);
        for v in [first, count, n] {
            wire::put_i32(
                out,
                i32::try_from(v).expect("marker counts are bounded by FrameBuf"),
            );
        }
        for &v in &frame.positions()[3 * first..3 * (first + count)] {
            wire::put_f32(out, v);
        }
        wire::end_element(out, at);
        Ok(out.len())
    }
}

/// Encodes the components profile into `out` (cleared first). Returns the encoded length.
///
/// One bundle: `/emoshift/stream ,is`, `/emoshift/components ,f...` carrying u, and with
/// `vmc` labels one `/VMC/Ext/Blend/Val ,sf` per (name, component index) label and a closing
/// `/VMC/Ext/Blend/Apply`, as VMC receivers expect values then apply in one datagram. Labels
/// naming a component past `u` are skipped.
///
/// # Errors
/// [`EncodeError::NulInString`] for a NUL in a label; the stream tag as
/// [`encode_compact_into`].
pub fn encode_components_into<S: AsRef<str>>(
    tag: &StreamTag<'_>,
    u: &[f32],
    vmc: &[(S, usize)],
    out: &mut Vec<u8>,
) -> Result<usize, EncodeError> {
    begin_stream_bundle(tag, out)?;
    let at = wire::begin_element(out);
    append_components(u, out);
    wire::end_element(out, at);
    if vmc.is_empty() {
        return Ok(out.len());
    }
    for (name, i) in vmc {
        let Some(&value) = u.get(*i) else { continue };
        let at = wire::begin_element(out);
        wire::put_str_unchecked(out, VMC_BLEND_VAL);
        wire::put_str_unchecked(out, ",sf");
        if let Err(e) = wire::put_str(out, name.as_ref()) {
            out.clear();
            return Err(e);
        }
        wire::put_f32(out, value);
        wire::end_element(out, at);
    }
    let at = wire::begin_element(out);
    wire::put_str_unchecked(out, VMC_BLEND_APPLY);
    wire::put_str_unchecked(out, ",");
    wire::end_element(out, at);
    Ok(out.len())
}

fn append_components(u: &[f32], out: &mut Vec<u8>) {
    let start = out.len();
    wire::put_prologue(out, start, COMPONENTS, b"", b'f', u.len());
    for &v in u {
        wire::put_f32(out, v);
    }
}
