//! Speech content: a sentence is a fixed viseme sequence with stresses, and four articulatory
//! sources follow it with co-articulation (Cohen-Massaro dominance blending), plus the sparse
//! eyebrow emphasis that goes with the sentence's stressed syllables.
//!
//! Everything here lives in *canonical* time (seconds from the sentence start); each take maps
//! its frames onto canonical time through its [`Warp`](super::warp::Warp).

use rand::Rng;
use serde::{Deserialize, Serialize};

use super::seeds::{sub_rng, Stream};

/// Number of speech sources.
pub const SPEECH_SOURCES: usize = 4;
/// Names of the speech sources, in source order.
pub const SPEECH_SOURCE_NAMES: [&str; SPEECH_SOURCES] =
    ["jaw_open", "lip_round", "lip_spread", "upper_lip_raise"];

/// A mouth shape class: each has targets for the four speech sources.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Viseme {
    /// Silence, mouth at rest.
    Rest,
    /// p, b, m: lips closed.
    Bilabial,
    /// f, v: lower lip against the upper teeth.
    Labiodental,
    /// th.
    Dental,
    /// t, d, n, s, z, l.
    Alveolar,
    /// sh, ch, j: rounded, protruded.
    Postalveolar,
    /// k, g.
    Velar,
    /// w, r: rounded glide.
    Glide,
    /// Open "aa".
    Aa,
    /// "ae" as in cat.
    Ae,
    /// "eh".
    Eh,
    /// Spread "ee".
    Ee,
    /// "ih".
    Ih,
    /// "oh".
    Oh,
    /// Rounded "oo".
    Oo,
    /// Schwa.
    Uh,
}

const CONSONANTS: [Viseme; 7] = [
    Viseme::Bilabial,
    Viseme::Labiodental,
    Viseme::Dental,
    Viseme::Alveolar,
    Viseme::Postalveolar,
    Viseme::Velar,
    Viseme::Glide,
];
const VOWELS: [Viseme; 8] = [
    Viseme::Aa,
    Viseme::Ae,
    Viseme::Eh,
    Viseme::Ee,
    Viseme::Ih,
    Viseme::Oh,
    Viseme::Oo,
    Viseme::Uh,
];

impl Viseme {
    /// Targets for (jaw_open, lip_round, lip_spread, upper_lip_raise).
    pub fn targets(self) -> [f64; SPEECH_SOURCES] {
        match self {
            Viseme::Rest => [0.0, 0.0, 0.0, 0.0],
            Viseme::Bilabial => [0.05, 0.1, 0.0, -0.5],
            Viseme::Labiodental => [0.12, 0.0, 0.1, 0.5],
            Viseme::Dental => [0.25, 0.0, 0.2, 0.1],
            Viseme::Alveolar => [0.18, 0.0, 0.3, 0.05],
            Viseme::Postalveolar => [0.18, 0.6, 0.0, 0.35],
            Viseme::Velar => [0.35, 0.0, 0.1, 0.0],
            Viseme::Glide => [0.2, 0.8, 0.0, 0.1],
            Viseme::Aa => [1.0, 0.0, 0.2, 0.2],
            Viseme::Ae => [0.8, 0.0, 0.6, 0.3],
            Viseme::Eh => [0.55, 0.0, 0.5, 0.2],
            Viseme::Ee => [0.25, 0.0, 1.0, 0.2],
            Viseme::Ih => [0.35, 0.0, 0.6, 0.1],
            Viseme::Oh => [0.6, 0.7, 0.0, 0.1],
            Viseme::Oo => [0.3, 1.0, 0.0, 0.05],
            Viseme::Uh => [0.4, 0.1, 0.15, 0.05],
        }
    }

    /// Dominance strength per source: how hard this segment pulls its neighbours towards its
    /// targets. Closures (p/b/m, f/v) must be reached, so they dominate the lips; tongue
    /// consonants leave the lips free (low lip dominance) so vowel rounding spreads over them.
    fn dominance(self) -> [f64; SPEECH_SOURCES] {
        match self {
            Viseme::Rest => [1.0, 1.0, 1.0, 1.0],
            Viseme::Bilabial => [1.5, 1.0, 1.0, 3.0],
            Viseme::Labiodental => [1.2, 0.8, 0.8, 2.5],
            Viseme::Postalveolar => [0.8, 2.0, 1.0, 1.0],
            Viseme::Glide => [0.6, 2.0, 1.0, 0.6],
            Viseme::Dental | Viseme::Alveolar | Viseme::Velar => [0.9, 0.25, 0.4, 0.3],
            _ => [1.0, 1.0, 1.0, 1.0],
        }
    }

    /// Whether this is a vowel (carries stress).
    pub fn is_vowel(self) -> bool {
        VOWELS.contains(&self)
    }
}

/// One segment of a sentence in canonical time.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Segment {
    /// Mouth shape.
    pub viseme: Viseme,
    /// Start, canonical seconds.
    pub start_s: f64,
    /// End, canonical seconds.
    pub end_s: f64,
    /// 0 unstressed, 1 secondary, 2 primary (vowels only).
    pub stress: u8,
}

/// A sparse eyebrow raise tied to a stressed syllable.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BrowEvent {
    /// Peak time, canonical seconds.
    pub peak_s: f64,
    /// Peak value of the `brow_raise` source.
    pub amplitude: f64,
}

/// Rise and fall widths of a brow raise (canonical seconds).
const BROW_RISE_S: f64 = 0.15;
const BROW_FALL_S: f64 = 0.35;

/// A sentence: fixed content shared by every take that utters it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Sentence {
    /// 0-based sentence index.
    pub index: usize,
    /// Sentence id as used in file names (`s01`, `s02`, ...).
    pub id: String,
    /// Viseme segments, contiguous, from 0 to `duration_s`.
    pub segments: Vec<Segment>,
    /// Eyebrow emphasis events.
    pub brow_events: Vec<BrowEvent>,
    /// Canonical duration, seconds.
    pub duration_s: f64,
}

/// Sentence id for a 0-based index: `s01`, ..., zero-padded to at least two digits.
pub fn sentence_id(index: usize, count: usize) -> String {
    let width = count.to_string().len().max(2);
    format!("s{:0width$}", index + 1)
}

impl Sentence {
    /// Generates sentence `index` of a corpus of `count` sentences for a session seed.
    pub fn generate(seed: u64, index: usize, count: usize) -> Sentence {
        let mut rng = sub_rng(seed, Stream::Sentence, index as u64, 0);
        let n_syll = rng.random_range(8..=14usize);
        let phrase_break = rng
            .random_bool(0.5)
            .then(|| rng.random_range(3..n_syll - 3));
        let stresses = stress_pattern(&mut rng, n_syll, phrase_break);
        let mut segs = Vec::new();
        let mut t = 0.0;
        let mut push = |v: Viseme, dur: f64, stress: u8, t: &mut f64| {
            segs.push(Segment {
                viseme: v,
                start_s: *t,
                end_s: *t + dur,
                stress,
            });
            *t += dur;
        };
        push(Viseme::Rest, 0.3, 0, &mut t);
        for (s, &stress) in stresses.iter().enumerate() {
            if phrase_break == Some(s) {
                push(Viseme::Rest, 0.15, 0, &mut t);
            }
            if rng.random_bool(0.85) {
                let c = CONSONANTS[rng.random_range(0..CONSONANTS.len())];
                push(c, rng.random_range(0.06..0.10), 0, &mut t);
            }
            let v = VOWELS[rng.random_range(0..VOWELS.len())];
            let lengthen = [1.0, 1.15, 1.35][stress as usize];
            push(v, rng.random_range(0.09..0.16) * lengthen, stress, &mut t);
            if rng.random_bool(0.35) {
                let c = CONSONANTS[rng.random_range(0..CONSONANTS.len())];
                push(c, rng.random_range(0.06..0.10), 0, &mut t);
            }
        }
        push(Viseme::Rest, 0.3, 0, &mut t);
        let brow_events = brow_events(&mut rng, &segs);
        Sentence {
            index,
            id: sentence_id(index, count),
            segments: segs,
            brow_events,
            duration_s: t,
        }
    }

    /// The four speech sources at canonical time `t`: dominance-weighted blend of every
    /// segment's (stress-scaled) targets, so neighbours co-articulate smoothly.
    pub fn speech_at(&self, t: f64) -> [f64; SPEECH_SOURCES] {
        let mut num = [0.0; SPEECH_SOURCES];
        let mut den = [0.0; SPEECH_SOURCES];
        for seg in &self.segments {
            let centre = 0.5 * (seg.start_s + seg.end_s);
            // The dominance reach grows with the segment's length (long vowels spread further).
            let width = 0.6 * (seg.end_s - seg.start_s) + 0.04;
            let fall = (-((t - centre).abs() / width).powf(1.5)).exp();
            let stress = f64::from(seg.stress);
            let mut target = seg.viseme.targets();
            target[0] *= 1.0 + 0.15 * stress;
            target[1] *= 1.0 + 0.1 * stress;
            target[2] *= 1.0 + 0.1 * stress;
            let alpha = seg.viseme.dominance();
            for k in 0..SPEECH_SOURCES {
                let d = alpha[k] * (1.0 + 0.3 * stress) * fall;
                num[k] += d * target[k];
                den[k] += d;
            }
        }
        // The floor only matters far outside the sentence, where everything decays: rest there.
        std::array::from_fn(|k| num[k] / (den[k] + 1e-12))
    }

    /// The `brow_raise` source at canonical time `t`.
    pub fn brow_at(&self, t: f64) -> f64 {
        self.brow_events
            .iter()
            .map(|e| {
                let dt = t - e.peak_s;
                let w = if dt < 0.0 { BROW_RISE_S } else { BROW_FALL_S };
                e.amplitude * (-(dt / w).powi(2)).exp()
            })
            .sum()
    }
}

/// One primary stress per phrase, sparse secondary stresses never next to a primary one.
fn stress_pattern(rng: &mut impl Rng, n: usize, phrase_break: Option<usize>) -> Vec<u8> {
    let mut stress = vec![0u8; n];
    let phrases = match phrase_break {
        Some(b) => vec![(0, b), (b, n)],
        None => vec![(0, n)],
    };
    for (a, b) in phrases {
        stress[rng.random_range(a..b)] = 2;
    }
    for i in 0..n {
        let near_primary = (i > 0 && stress[i - 1] == 2) || (i + 1 < n && stress[i + 1] == 2);
        if stress[i] == 0 && !near_primary && rng.random_bool(0.3) {
            stress[i] = 1;
        }
    }
    stress
}

/// Brow raises lead the accent: they peak 0.1-0.35 s before the stressed vowel's onset and
/// decay over the next syllable or two; every primary stress, a sixth of the secondary ones.
/// (Peaking on the vowel itself would tie them to the jaw opening far more than real brows are,
/// and no linear method could then tell emphasis from speech.)
fn brow_events(rng: &mut impl Rng, segs: &[Segment]) -> Vec<BrowEvent> {
    let mut events = Vec::new();
    for seg in segs.iter().filter(|s| s.stress > 0) {
        let amplitude = match seg.stress {
            2 => rng.random_range(0.8..1.2),
            _ if rng.random_bool(1.0 / 6.0) => rng.random_range(0.4..0.7),
            _ => continue,
        };
        let peak_s = seg.start_s - rng.random_range(0.1..0.35);
        events.push(BrowEvent { peak_s, amplitude });
    }
    events
}

#[cfg(test)]
mod tests;
