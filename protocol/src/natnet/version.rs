//! [`NatNetVersion`] and the layout rules it selects (see the table in the module docs).

use std::fmt;

use super::error::NatNetError;

/// A NatNet protocol (bitstream) version, as four bytes on the wire:
/// major, minor, build, revision. Ordered lexicographically.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub struct NatNetVersion {
    /// Major version: 3 for Motive 2.x, 4 for Motive 3.x.
    pub major: u8,
    /// Minor version.
    pub minor: u8,
    /// Build number.
    pub build: u8,
    /// Revision.
    pub revision: u8,
}

impl NatNetVersion {
    /// NatNet 3.0.0.0 (Motive 2.0 and 2.1).
    pub const V3_0: NatNetVersion = NatNetVersion::new(3, 0, 0, 0);
    /// NatNet 3.1.0.0 (Motive 2.2 and 2.3).
    pub const V3_1: NatNetVersion = NatNetVersion::new(3, 1, 0, 0);
    /// NatNet 4.0.0.0 (Motive 3.0).
    pub const V4_0: NatNetVersion = NatNetVersion::new(4, 0, 0, 0);
    /// NatNet 4.1.0.0 (Motive 3.1 and later).
    pub const V4_1: NatNetVersion = NatNetVersion::new(4, 1, 0, 0);

    /// A version from its four parts.
    pub const fn new(major: u8, minor: u8, build: u8, revision: u8) -> Self {
        NatNetVersion {
            major,
            minor,
            build,
            revision,
        }
    }

    /// From the wire's four bytes.
    pub const fn from_bytes(b: [u8; 4]) -> Self {
        NatNetVersion::new(b[0], b[1], b[2], b[3])
    }

    /// The wire's four bytes.
    pub const fn to_bytes(self) -> [u8; 4] {
        [self.major, self.minor, self.build, self.revision]
    }

    /// Whether frames and model definitions of this version can be decoded and encoded:
    /// NatNet 3.x and 4.x.
    pub const fn is_supported(self) -> bool {
        self.major == 3 || self.major == 4
    }

    /// `Ok(())` for a supported version, else [`NatNetError::UnsupportedVersion`].
    ///
    /// # Errors
    ///
    /// Versions before 3.0 (rigid bodies with marker lists, float timestamps, no high-resolution
    /// clock) and after 4.x (unknown layout) are refused rather than guessed.
    pub const fn check(self) -> Result<(), NatNetError> {
        if self.is_supported() {
            Ok(())
        } else {
            Err(NatNetError::UnsupportedVersion {
                major: self.major,
                minor: self.minor,
            })
        }
    }

    /// NatNet 4.1+: every frame section and every data description is preceded by its size in
    /// bytes, and frames carry the asset (trained markerset) section.
    pub const fn has_section_sizes(self) -> bool {
        (self.major == 4 && self.minor >= 1) || self.major > 4
    }

    /// NatNet 4.1+: the frame suffix carries a precision (PTP) timestamp. The SDK's C++
    /// PacketClient reads it from 4.1; its Python client from 4.0 — see
    /// [`FrameOfData`](super::FrameOfData) for how 4.0 frames are told apart.
    pub const fn has_precision_timestamp(self) -> bool {
        self.has_section_sizes()
    }

    /// NatNet 4.0+: rigid body descriptions carry a name per marker.
    pub const fn has_rigid_body_marker_names(self) -> bool {
        self.major >= 4
    }
}

impl fmt::Display for NatNetVersion {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}.{}.{}.{}",
            self.major, self.minor, self.build, self.revision
        )
    }
}

/// Parses the reply to the `Bitstream` request (`"Bitstream,4.0"` or `"Bitstream,4.0.0"`):
/// with NatNet 4 in unicast, a client can switch the server's bitstream version, and frames
/// follow the new version from then on.
pub fn parse_bitstream_reply(text: &str) -> Option<NatNetVersion> {
    let rest = text.strip_prefix("Bitstream,")?;
    let mut parts = [0u8; 4];
    let mut n = 0;
    for p in rest.trim_end_matches('\0').split('.') {
        *parts.get_mut(n)? = p.trim().parse().ok()?;
        n += 1;
    }
    (n >= 2).then(|| NatNetVersion::from_bytes(parts))
}

#[cfg(test)]
mod tests;
