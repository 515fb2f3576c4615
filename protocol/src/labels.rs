//! `/mocap/labels ,i s...` and the per-source layout binding of frames ([`LayoutBook`]).

use std::collections::HashMap;
use std::hash::Hash;

use rosc::OscType;

use crate::address::LABELS;
use crate::error::{DecodeError, EncodeError};
use crate::frame::MAX_FRAME_MARKERS;
use crate::wire;

/// A layout: its id and its marker names in frame order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Labels {
    /// Sender-chosen layout id.
    pub layout_id: i32,
    /// Marker names, non-empty and distinct, in the order of frame positions.
    pub names: Vec<String>,
}

/// Decodes a `/mocap/labels` message with rosc after the crate's own pre-scan.
///
/// # Errors
/// [`DecodeError::UnknownAddress`] for another address, [`DecodeError::WrongTypeTags`] unless
/// the tags are `,i` followed by one or more `s`, [`DecodeError::OutOfRange`] (argument index)
/// for an empty or repeated name, [`DecodeError::TooManyMarkers`], and any structural error.
pub fn decode_labels(msg: &[u8]) -> Result<Labels, DecodeError> {
    let m = crate::control::decode_osc(msg)?;
    if m.addr != LABELS {
        return Err(DecodeError::UnknownAddress);
    }
    let mut args = m.args.into_iter();
    let Some(OscType::Int(layout_id)) = args.next() else {
        return Err(DecodeError::WrongTypeTags);
    };
    let mut names = Vec::with_capacity(args.len());
    for (i, a) in args.enumerate() {
        let OscType::String(name) = a else {
            return Err(DecodeError::WrongTypeTags);
        };
        if name.is_empty() {
            return Err(DecodeError::OutOfRange { index: i + 1 });
        }
        if names.contains(&name) {
            return Err(DecodeError::DuplicateLabel { index: i + 1 });
        }
        names.push(name);
    }
    if names.is_empty() {
        return Err(DecodeError::WrongTypeTags);
    }
    if names.len() > MAX_FRAME_MARKERS {
        return Err(DecodeError::TooManyMarkers {
            markers: names.len(),
            max: MAX_FRAME_MARKERS,
        });
    }
    Ok(Labels { layout_id, names })
}

/// Encodes `/mocap/labels ,i s...` into `out` (cleared first). Returns the encoded length.
///
/// # Errors
/// [`EncodeError::NulInString`] if a name contains a NUL byte.
pub fn encode_labels_into(labels: &Labels, out: &mut Vec<u8>) -> Result<usize, EncodeError> {
    out.clear();
    wire::put_prologue(out, 0, LABELS, b"i", b's', labels.names.len());
    wire::put_i32(out, labels.layout_id);
    for name in &labels.names {
        if let Err(e) = wire::put_str(out, name) {
            out.clear();
            return Err(e);
        }
    }
    Ok(out.len())
}

/// Layouts a source may keep at once (one per marker count); the least recent goes first.
pub const MAX_LAYOUTS_PER_SOURCE: usize = 8;

/// What [`LayoutBook::handle_labels`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LayoutChange {
    /// First layout of this marker count from this source.
    Added,
    /// Same id and names as the one held: nothing changed (the every-second repeat).
    Unchanged,
    /// A different layout replaced the one of the same marker count.
    Replaced,
    /// The book already tracks its maximum number of sources; labels ignored.
    Rejected,
}

/// Binds frames to layouts, per source.
///
/// The rule (frames carry no layout id, so `,ihbb` stays as specified): **a frame's layout is
/// the latest `/mocap/labels` from the same source whose marker count equals the frame's.** A
/// source may interleave layouts of different sizes; two layouts of the same size from one
/// source replace each other, so such a source must send them from different ports. `K` is
/// whatever identifies a source for the caller (the daemon uses the peer `SocketAddr`).
#[derive(Debug, Clone)]
pub struct LayoutBook<K> {
    sources: HashMap<K, Vec<Labels>>,
    max_sources: usize,
}

impl<K: Eq + Hash + Clone> LayoutBook<K> {
    /// A book tracking at most `max_sources` sources (bounds memory against spoofed senders).
    pub fn new(max_sources: usize) -> Self {
        LayoutBook {
            sources: HashMap::new(),
            max_sources,
        }
    }

    /// Records labels received from `source`.
    pub fn handle_labels(&mut self, source: &K, labels: Labels) -> LayoutChange {
        if !self.sources.contains_key(source) && self.sources.len() >= self.max_sources {
            return LayoutChange::Rejected;
        }
        let held = self.sources.entry(source.clone()).or_default();
        let same_size = held
            .iter()
            .position(|l| l.names.len() == labels.names.len());
        let change = match same_size {
            Some(i) if held[i] == labels => {
                let l = held.remove(i);
                held.push(l);
                return LayoutChange::Unchanged;
            }
            Some(i) => {
                held.remove(i);
                LayoutChange::Replaced
            }
            None => LayoutChange::Added,
        };
        if held.len() >= MAX_LAYOUTS_PER_SOURCE {
            held.remove(0);
        }
        held.push(labels);
        change
    }

    /// The layout of a frame with `marker_count` markers from `source`, if its labels arrived.
    pub fn layout_for(&self, source: &K, marker_count: usize) -> Option<&Labels> {
        self.sources
            .get(source)?
            .iter()
            .find(|l| l.names.len() == marker_count)
    }

    /// Forgets a source (e.g. after it timed out).
    pub fn forget(&mut self, source: &K) {
        self.sources.remove(source);
    }

    /// Sources currently tracked.
    pub fn source_count(&self) -> usize {
        self.sources.len()
    }
}

#[cfg(test)]
mod tests;
