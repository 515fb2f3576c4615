//! Encoding a processed frame once per profile the subscribers want.

use protocol::{
    append_timecode_element, encode_compact_into, encode_components_into, FlatSplit, FrameBuf,
    FrameTime, Profile, StreamTag, ETHERNET_PAYLOAD,
};

use crate::engine::edit_state::EditState;

/// Profiles to encode, as a bit set (`1 << profile index` in [`Profile::ALL`]).
pub type ProfileMask = u8;

/// The bit of one profile.
pub fn profile_bit(p: Profile) -> ProfileMask {
    match p {
        Profile::Compact => 1,
        Profile::FlatSplit => 2,
        Profile::Components => 4,
    }
}

/// The encoded output of one frame, one buffer per profile, reused frame after frame.
#[derive(Debug)]
pub(super) struct Outputs {
    split: FlatSplit,
    /// Compact bundle (empty when not wanted).
    pub(super) compact: Vec<u8>,
    /// Components message (empty when not wanted).
    pub(super) components: Vec<u8>,
    /// One flat-split part, encoded before it is appended to `parts`.
    part: Vec<u8>,
    /// Flat-split parts, concatenated.
    pub(super) parts: Vec<u8>,
    /// End offset of each part in `parts`.
    pub(super) part_ends: Vec<usize>,
}

impl Outputs {
    /// Buffers for frames of up to `max_markers` markers.
    pub(super) fn new(max_markers: usize) -> Outputs {
        Outputs {
            split: FlatSplit::new(ETHERNET_PAYLOAD).expect("an Ethernet payload holds a marker"),
            compact: Vec::with_capacity(ETHERNET_PAYLOAD),
            components: Vec::with_capacity(ETHERNET_PAYLOAD),
            part: Vec::with_capacity(ETHERNET_PAYLOAD),
            parts: Vec::with_capacity(16 * max_markers + 4 * ETHERNET_PAYLOAD),
            part_ends: Vec::with_capacity(max_markers),
        }
    }

    /// Encodes `frame` once for each profile in `wanted`, with the stream's edit state (for
    /// the compact state message), its components `u` and their VMC names. The source's
    /// `time` rides in the compact and components bundles as `/mocap/timecode` when there is
    /// one (flat-split parts stay within their size budget without it).
    pub(super) fn encode(
        &mut self,
        wanted: ProfileMask,
        tag: &StreamTag<'_>,
        frame: &FrameBuf,
        edit: &EditState,
        (u, vmc): (&[f32], &[(String, usize)]),
        time: &FrameTime,
    ) -> Result<(), protocol::EncodeError> {
        self.compact.clear();
        self.components.clear();
        self.parts.clear();
        self.part_ends.clear();
        if wanted & profile_bit(Profile::Compact) != 0 {
            encode_compact_into(tag, frame, edit.target(), edit.amount(), &mut self.compact)?;
            if time.is_some() {
                append_timecode_element(time, &mut self.compact);
            }
        }
        if wanted & profile_bit(Profile::Components) != 0 {
            encode_components_into(tag, u, vmc, &mut self.components)?;
            if time.is_some() {
                append_timecode_element(time, &mut self.components);
            }
        }
        if wanted & profile_bit(Profile::FlatSplit) != 0 {
            for i in 0..self.split.part_count(frame.marker_count()) {
                self.split.encode_part_into(tag, frame, i, &mut self.part)?;
                self.parts.extend_from_slice(&self.part);
                self.part_ends.push(self.parts.len());
            }
        }
        Ok(())
    }
}
