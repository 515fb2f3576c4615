//! Encoding a processed frame once per profile the subscribers want.

use protocol::{encode_compact_into, encode_components_into, FlatSplit, FrameBuf, Profile};

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

/// Encodes the wanted profiles of one frame into the pipeline's buffers.
pub(super) fn encode(
    wanted: ProfileMask,
    frame: &FrameBuf,
    edit: &crate::engine::edit_state::EditState,
    (u, vmc): (&[f32], &[(String, usize)]),
    split: &FlatSplit,
    [compact, components, part, parts]: [&mut Vec<u8>; 4],
    part_ends: &mut Vec<usize>,
) -> Result<(), protocol::EncodeError> {
    compact.clear();
    components.clear();
    parts.clear();
    part_ends.clear();
    if wanted & profile_bit(Profile::Compact) != 0 {
        encode_compact_into(frame, edit.target(), edit.amount(), compact)?;
    }
    if wanted & profile_bit(Profile::Components) != 0 {
        encode_components_into(u, vmc, components)?;
    }
    if wanted & profile_bit(Profile::FlatSplit) != 0 {
        for i in 0..split.part_count(frame.marker_count()) {
            split.encode_part_into(frame, i, part);
            parts.extend_from_slice(part);
            part_ends.push(parts.len());
        }
    }
    Ok(())
}
