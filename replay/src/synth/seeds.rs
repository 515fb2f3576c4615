//! Independent, reproducible random streams derived from one session seed.
//!
//! Every random quantity draws from its own ChaCha8 stream keyed by (seed, purpose, a, b), so
//! adding a take or a sentence never shifts the numbers of another one.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// What a random stream is used for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Stream {
    /// Sentence content (visemes, stresses, brow events); keyed by sentence.
    Sentence = 1,
    /// Per-take seed; keyed by sentence and emotion index.
    Take = 2,
    /// Per-(sentence, emotion) intensity of the emotion.
    Intensity = 3,
    /// Timing warp of a take; keyed by take seed.
    Warp = 4,
    /// Emotion drift within a take.
    Drift = 5,
    /// Blink events.
    Blink = 6,
    /// Rigid head motion.
    Head = 7,
    /// Sensor noise.
    Noise = 8,
    /// Marker placement of a jittered layout.
    Layout = 9,
    /// Emotion drift of a take on emotion directions after the first; keyed by take seed and
    /// direction (the first keeps [`Stream::Drift`]).
    DirectionDrift = 10,
    /// Which sentences an emotion with fewer takes is spoken in; keyed by emotion name.
    Subset = 11,
    /// Emotion x sentence offset of a point; keyed by sentence and emotion name.
    Interaction = 12,
    /// Spread effects of an emotion direction; keyed by direction.
    Spread = 13,
}

/// SplitMix64 finaliser: a cheap, well-mixed bijection on u64.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A 64-bit key for (seed, stream, a, b).
pub(crate) fn sub_seed(seed: u64, stream: Stream, a: u64, b: u64) -> u64 {
    mix(mix(mix(seed ^ mix(stream as u64)) ^ a) ^ mix(b.wrapping_add(0x5555)))
}

/// The random stream for (seed, stream, a, b).
pub(crate) fn sub_rng(seed: u64, stream: Stream, a: u64, b: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(sub_seed(seed, stream, a, b))
}

/// FNV-1a of a name, to key streams by emotion name rather than by list position.
pub(crate) fn name_key(name: &str) -> u64 {
    name.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01B3)
    })
}
