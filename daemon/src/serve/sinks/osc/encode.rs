//! A processed frame encoded once per OSC profile its subscribers want, each profile as a list
//! of datagrams (compact: one bundle; flat-split: one per part; components: one), in buffers
//! reused frame after frame. Sending is then the same loop for every profile.

use engine::Processed;
use protocol::{
    append_timecode_element, encode_compact_into, encode_components_into, EncodeError, FlatSplit,
    Profile, ETHERNET_PAYLOAD,
};

use super::streams::StreamNames;

/// Profiles as a bit set (`1 << index in Profile::ALL`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Profiles(u8);

impl Profiles {
    /// The set holding `p` too.
    pub fn with(self, p: Profile) -> Profiles {
        Profiles(self.0 | 1 << index(p))
    }

    /// Whether it holds `p`.
    pub fn contains(self, p: Profile) -> bool {
        self.0 & 1 << index(p) != 0
    }

    /// Whether it holds none.
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }
}

/// The position of `p` in [`Profile::ALL`].
pub fn index(p: Profile) -> usize {
    Profile::ALL.iter().position(|&q| q == p).unwrap_or(0)
}

/// One profile's datagrams of a frame, concatenated.
#[derive(Debug, Default)]
struct Datagrams {
    bytes: Vec<u8>,
    /// End offset of each datagram in `bytes`.
    ends: Vec<usize>,
}

impl Datagrams {
    fn with_capacity(bytes: usize, datagrams: usize) -> Datagrams {
        Datagrams {
            bytes: Vec::with_capacity(bytes),
            ends: Vec::with_capacity(datagrams),
        }
    }

    fn clear(&mut self) {
        self.bytes.clear();
        self.ends.clear();
    }

    /// Ends the datagram written at the end of `bytes`.
    fn end(&mut self) {
        self.ends.push(self.bytes.len());
    }

    fn iter(&self) -> impl Iterator<Item = &[u8]> {
        let starts = std::iter::once(0).chain(self.ends.iter().copied());
        starts.zip(&self.ends).map(|(a, &b)| &self.bytes[a..b])
    }
}

/// Encodes one profile of a frame into its datagrams.
type EncodeFn = fn(&mut Encoder, &Processed<'_>, &StreamNames) -> Result<(), EncodeError>;

/// Each profile's encoder, in [`Profile::ALL`] order.
const ENCODERS: [EncodeFn; 3] = [Encoder::compact, Encoder::flat_split, Encoder::components];

/// The encoded frame, one list of datagrams per profile.
#[derive(Debug)]
pub struct Encoder {
    split: FlatSplit,
    /// One flat-split part, before it is appended.
    part: Vec<u8>,
    out: [Datagrams; 3],
}

impl Encoder {
    /// Buffers for frames of up to `max_markers` markers.
    pub fn new(max_markers: usize) -> Encoder {
        let one = || Datagrams::with_capacity(ETHERNET_PAYLOAD, 1);
        Encoder {
            split: FlatSplit::new(ETHERNET_PAYLOAD).expect("an Ethernet payload holds a marker"),
            part: Vec::with_capacity(ETHERNET_PAYLOAD),
            out: [
                one(),
                Datagrams::with_capacity(16 * max_markers + 4 * ETHERNET_PAYLOAD, max_markers),
                one(),
            ],
        }
    }

    /// Encodes `frame` once for each profile in `wanted` (the others are left empty).
    ///
    /// # Errors
    /// The first profile that cannot be encoded (its datagrams are then left empty).
    pub fn encode(
        &mut self,
        wanted: Profiles,
        frame: &Processed<'_>,
        names: &StreamNames,
    ) -> Result<(), EncodeError> {
        for (i, profile) in Profile::ALL.into_iter().enumerate() {
            self.out[i].clear();
            if wanted.contains(profile) {
                if let Err(e) = ENCODERS[i](self, frame, names) {
                    self.out[i].clear();
                    return Err(e);
                }
            }
        }
        Ok(())
    }

    /// The datagrams of `profile` for the frame last encoded (none when not wanted).
    pub fn datagrams(&self, profile: Profile) -> impl Iterator<Item = &[u8]> {
        self.out[index(profile)].iter()
    }

    /// The frame and the emotion state in one bundle, with the source's timecode when there
    /// is one.
    fn compact(&mut self, f: &Processed<'_>, _: &StreamNames) -> Result<(), EncodeError> {
        let out = &mut self.out[index(Profile::Compact)];
        let edit = &f.stream.edit;
        let tag = f.identity().tag();
        encode_compact_into(&tag, f.output, edit.target(), edit.amount(), &mut out.bytes)?;
        if f.time.is_some() {
            append_timecode_element(f.time, &mut out.bytes);
        }
        out.end();
        Ok(())
    }

    /// The frame in parts within the Ethernet payload (no timecode: it would not fit).
    fn flat_split(&mut self, f: &Processed<'_>, _: &StreamNames) -> Result<(), EncodeError> {
        let tag = f.identity().tag();
        let out = &mut self.out[index(Profile::FlatSplit)];
        for i in 0..self.split.part_count(f.output.marker_count()) {
            self.split
                .encode_part_into(&tag, f.output, i, &mut self.part)?;
            out.bytes.extend_from_slice(&self.part);
            out.end();
        }
        Ok(())
    }

    /// The components, with their VMC blend names, and the source's timecode.
    fn components(&mut self, f: &Processed<'_>, names: &StreamNames) -> Result<(), EncodeError> {
        let out = &mut self.out[index(Profile::Components)];
        let tag = f.identity().tag();
        encode_components_into(&tag, f.stream.components(), &names.vmc, &mut out.bytes)?;
        if f.time.is_some() {
            append_timecode_element(f.time, &mut out.bytes);
        }
        out.end();
        Ok(())
    }
}

/// A sink that encodes every frame in `profiles` and sends nothing: what the OSC output does
/// for its subscribers minus the sockets (the benches' and the allocation test's stand-in).
#[derive(Debug)]
pub struct EncodeOnly {
    /// The profiles encoded.
    pub profiles: Profiles,
    encoder: Encoder,
    names: super::streams::Names,
    /// Bytes encoded so far, over every profile.
    pub bytes: u64,
    /// Frames that could not be encoded.
    pub errors: u64,
}

impl EncodeOnly {
    /// Encodes `profiles` of frames of up to `max_markers` markers.
    pub fn new(profiles: Profiles, max_markers: usize) -> EncodeOnly {
        EncodeOnly {
            profiles,
            encoder: Encoder::new(max_markers),
            names: super::streams::Names::default(),
            bytes: 0,
            errors: 0,
        }
    }

    /// Every profile.
    pub fn all(max_markers: usize) -> EncodeOnly {
        let all = Profile::ALL
            .into_iter()
            .fold(Profiles::default(), Profiles::with);
        EncodeOnly::new(all, max_markers)
    }
}

impl engine::Sink for EncodeOnly {
    fn needs(&self) -> engine::Needs {
        engine::Needs {
            markers: true,
            components: true,
            state: true,
            labels: true,
            input: false,
            time: true,
        }
    }

    fn handle_frame(&mut self, frame: &Processed<'_>) {
        let names = self.names.of(frame);
        if self.encoder.encode(self.profiles, frame, names).is_err() {
            self.errors += 1;
            return;
        }
        for p in Profile::ALL {
            self.bytes += self
                .encoder
                .datagrams(p)
                .map(|d| d.len() as u64)
                .sum::<u64>();
        }
    }
}
