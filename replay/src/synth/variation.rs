//! Session variants the emotion method was not built around, each with its truth (issue 34).
//!
//! The default generator agrees with the method by construction: every emotion is one
//! independent source per direction, moved by one field, spoken in every sentence at the same
//! pace, with a small intensity change per take. A [`Variation`] breaks one agreement at a time
//! (or several together):
//!
//! | knob | what the session does | the truth of an edit to emotion B |
//! |---|---|---|
//! | `take_intensity` | each take its own intensity, `1 ± take_intensity` | B's average take in the session: the edit must remove the take's own intensity, not its emotion's |
//! | `spread_effects` | ([`super::spread`]) each emotion direction also moves the speech, brow and lid fields and a smooth field over the whole face | B's take of the sentence, as by default |
//! | `takes` | `angry=3`: an emotion spoken in only that many sentences (drawn by the seed) | as by default |
//! | `interaction` | each (sentence, emotion) point moves by a random offset of this standard deviation per direction | B's point on that sentence, offset included |
//! | `speech_rate` | `angry=1.2`: that emotion speaks 20 % faster | B at the original take's timing |
//!
//! Other face layouts come from [`super::Layout`]. The default `Variation` changes nothing: a
//! session is then the same, bit for bit, as before variants existed.

use std::str::FromStr;

use rand::Rng;
use rand_distr::{Distribution, Normal};

use super::seeds::{name_key, sub_rng, Stream};
use super::SynthError;

/// Largest per-take intensity spread: past it a take could show the opposite emotion.
pub const MAX_TAKE_INTENSITY: f64 = 0.9;
/// Largest strength of the spread effects.
pub const MAX_SPREAD_EFFECTS: f64 = 3.0;
/// Largest emotion x sentence interaction (standard deviation per direction).
pub const MAX_INTERACTION: f64 = 1.0;
/// Range of speech-rate factors: half to twice the canonical pace.
pub const SPEECH_RATE_RANGE: (f64, f64) = (0.5, 2.0);

/// `name=value`, e.g. `angry=3` or `sad=0.8`.
#[derive(Debug, Clone, PartialEq)]
pub struct NameValue {
    /// Emotion name.
    pub name: String,
    /// The value.
    pub value: f64,
}

impl FromStr for NameValue {
    type Err = SynthError;

    fn from_str(text: &str) -> Result<NameValue, SynthError> {
        let bad = || SynthError::NameValueSyntax {
            text: text.to_string(),
        };
        let (name, value) = text.split_once('=').ok_or_else(bad)?;
        let value: f64 = value.trim().parse().map_err(|_| bad())?;
        Ok(NameValue {
            name: name.trim().to_string(),
            value,
        })
    }
}

/// The variant knobs. See the module docs.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Variation {
    /// Per-take intensity spread (0: the default ±15 % per take, with the target's own
    /// intensity in the truth).
    pub take_intensity: f64,
    /// Strength of the spread effects (0: none).
    pub spread_effects: f64,
    /// Emotions spoken in fewer sentences than the session has: emotion and sentence count.
    pub takes: Vec<NameValue>,
    /// Standard deviation of the per-(sentence, emotion) offset of each point (0: none).
    pub interaction: f64,
    /// Speech-rate factor of some emotions (1: the canonical pace).
    pub speech_rate: Vec<NameValue>,
}

impl Variation {
    /// True when no knob is set: the default session.
    pub fn is_none(&self) -> bool {
        *self == Variation::default()
    }

    /// Checks the knobs against the session's emotions and sentence count.
    ///
    /// # Errors
    /// [`SynthError::BadVariation`] for a value out of range,
    /// [`SynthError::UnlistedVariation`] for a name not in the session,
    /// [`SynthError::RepeatedVariation`] for an emotion given twice.
    pub fn validate(&self, emotions: &[String], sentences: usize) -> Result<(), SynthError> {
        let range = |knob: &'static str, value: f64, lo: f64, hi: f64| {
            if value.is_finite() && (lo..=hi).contains(&value) {
                Ok(())
            } else {
                Err(SynthError::BadVariation {
                    knob,
                    value,
                    expected: format!("{lo} to {hi}"),
                })
            }
        };
        range(
            "take intensity",
            self.take_intensity,
            0.0,
            MAX_TAKE_INTENSITY,
        )?;
        range(
            "spread effects",
            self.spread_effects,
            0.0,
            MAX_SPREAD_EFFECTS,
        )?;
        range("interaction", self.interaction, 0.0, MAX_INTERACTION)?;
        let (lo, hi) = SPEECH_RATE_RANGE;
        for (knob, list) in [("takes", &self.takes), ("speech rate", &self.speech_rate)] {
            for (i, nv) in list.iter().enumerate() {
                if !emotions.contains(&nv.name) {
                    return Err(SynthError::UnlistedVariation {
                        knob,
                        emotion: nv.name.clone(),
                        known: emotions.join(", "),
                    });
                }
                if list[..i].iter().any(|o| o.name == nv.name) {
                    return Err(SynthError::RepeatedVariation {
                        knob,
                        emotion: nv.name.clone(),
                    });
                }
                if knob == "takes" {
                    let whole = nv.value.fract() == 0.0;
                    range(knob, nv.value, 1.0, sentences as f64)?;
                    if !whole {
                        return Err(SynthError::BadVariation {
                            knob,
                            value: nv.value,
                            expected: format!("a whole number of sentences, 1 to {sentences}"),
                        });
                    }
                } else {
                    range(knob, nv.value, lo, hi)?;
                }
            }
        }
        Ok(())
    }

    /// Speech-rate factor of `emotion` (1 unless set).
    pub fn rate_of(&self, emotion: &str) -> f64 {
        find(&self.speech_rate, emotion).unwrap_or(1.0)
    }

    /// Sentences `emotion` is spoken in, when fewer than all.
    pub fn takes_of(&self, emotion: &str) -> Option<usize> {
        find(&self.takes, emotion).map(|v| v as usize)
    }

    /// A short description, e.g. `take intensity ±0.4, angry in 3 sentences` (`none`).
    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        if self.take_intensity > 0.0 {
            parts.push(format!("take intensity ±{}", self.take_intensity));
        }
        if self.spread_effects > 0.0 {
            parts.push(format!("spread effects {}", self.spread_effects));
        }
        for t in &self.takes {
            parts.push(format!("{} in {} sentences", t.name, t.value));
        }
        if self.interaction > 0.0 {
            parts.push(format!("emotion x sentence {}", self.interaction));
        }
        for r in &self.speech_rate {
            parts.push(format!("{} speaks x{}", r.name, r.value));
        }
        if parts.is_empty() {
            "none".to_string()
        } else {
            parts.join(", ")
        }
    }
}

fn find(list: &[NameValue], emotion: &str) -> Option<f64> {
    list.iter().find(|nv| nv.name == emotion).map(|nv| nv.value)
}

/// Whether `emotion` is spoken in each of `sentences` sentences: all of them, or `count`
/// drawn by the seed (the same draw whatever the other emotions do).
pub(crate) fn spoken_in(
    seed: u64,
    emotion: &str,
    count: Option<usize>,
    sentences: usize,
) -> Vec<bool> {
    let Some(count) = count.filter(|&c| c < sentences) else {
        return vec![true; sentences];
    };
    let mut rng = sub_rng(seed, Stream::Subset, name_key(emotion), 0);
    let mut order: Vec<usize> = (0..sentences).collect();
    // Fisher-Yates: the first `count` of a uniform shuffle.
    for i in 0..count {
        let j = rng.random_range(i..sentences);
        order.swap(i, j);
    }
    let mut spoken = vec![false; sentences];
    for &s in &order[..count] {
        spoken[s] = true;
    }
    spoken
}

/// The per-take intensity factor, `1 ± spread`, of a take of `sentence` in `emotion`.
pub(crate) fn take_intensity(seed: u64, sentence: usize, emotion: &str, spread: f64) -> f64 {
    let mut rng = sub_rng(seed, Stream::Intensity, sentence as u64, name_key(emotion));
    1.0 + rng.random_range(-spread..spread)
}

/// How `emotion` shows on `sentence` beyond its point: one offset per direction.
pub(crate) fn interaction(
    seed: u64,
    sentence: usize,
    emotion: &str,
    dims: usize,
    std: f64,
) -> Vec<f64> {
    if std <= 0.0 {
        return vec![0.0; dims];
    }
    let mut rng = sub_rng(
        seed,
        Stream::Interaction,
        sentence as u64,
        name_key(emotion),
    );
    let normal = Normal::new(0.0, std).expect("a finite positive standard deviation");
    (0..dims).map(|_| normal.sample(&mut rng)).collect()
}

#[cfg(test)]
mod tests;
