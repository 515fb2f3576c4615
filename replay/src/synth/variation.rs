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
//! | `spread_effects` | each emotion direction also moves the speech, brow and lid fields and a smooth field over the whole face | B's take of the sentence, as by default |
//! | `takes` | `angry=3`: an emotion spoken in only that many sentences (drawn by the seed) | as by default |
//! | `interaction` | each (sentence, emotion) point moves by a random offset of this standard deviation per direction | B's point on that sentence, offset included |
//! | `speech_rate` | `angry=1.2`: that emotion speaks 20 % faster | B at the original take's timing |
//!
//! Other face layouts come from [`super::Layout`]. The default `Variation` changes nothing: a
//! session is then the same, bit for bit, as before variants existed.

use std::f64::consts::PI;
use std::str::FromStr;

use rand::Rng;
use rand_distr::{Distribution, Normal};

use super::columns::SourceLayout;
use super::geometry::{FaceGeometry, Region};
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
/// RMS over the face markers of the face-wide field a spread effect of strength 1 adds to an
/// emotion direction, mm per unit level.
pub const SPREAD_FIELD_MM: f64 = 1.5;
/// Largest shift of a speech or brow source per unit emotion level at strength 1.
const SPREAD_SHIFT: f64 = 0.3;
/// Smooth bumps making up a face-wide field.
const SPREAD_BUMPS: usize = 6;

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

/// Adds the spread effects of `strength` to the emotion columns of the mixing matrix `m`
/// (channels x `layout.count()`, row-major): each direction also moves the speech, brow and
/// lid fields by a random shift per unit level, and a smooth random field over the whole
/// face ([`SPREAD_FIELD_MM`] RMS at strength 1). Head-reference markers stay still.
pub(crate) fn add_spread_effects(
    m: &mut [f64],
    face: &FaceGeometry,
    layout: SourceLayout,
    seed: u64,
    strength: f64,
) {
    let count = layout.count();
    let others: Vec<usize> = (0..layout.speech_count())
        .chain([layout.brow_raise(), layout.blink()])
        .collect();
    let face_markers: Vec<usize> = (0..face.markers.len())
        .filter(|&i| face.markers[i].region != Region::HeadReference)
        .collect();
    for d in 0..layout.emotion_dims() {
        let mut rng = sub_rng(seed, Stream::Spread, d as u64, 0);
        let shifts: Vec<f64> = others
            .iter()
            .map(|&c| {
                let shift = rng.random_range(-SPREAD_SHIFT..SPREAD_SHIFT);
                // The blink field closes the lids at 1: a quarter of the shift keeps the lids
                // from half closing for a whole take.
                if c == layout.blink() {
                    0.25 * shift.abs()
                } else {
                    shift
                }
            })
            .collect();
        let field = face_field(face, &face_markers, &mut rng);
        let col = layout.emotion(d);
        for &i in &face_markers {
            for a in 0..3 {
                let row = (i * 3 + a) * count;
                let moved: f64 = others
                    .iter()
                    .zip(&shifts)
                    .map(|(&c, s)| s * m[row + c])
                    .sum();
                m[row + col] += strength * (moved + field[i * 3 + a]);
            }
        }
    }
}

/// A smooth random displacement field over the face: a random affine field (a tilt of the
/// whole face, so every region moves) plus a few Gaussian bumps at random markers, each with
/// its own direction, scaled to [`SPREAD_FIELD_MM`] RMS over `markers`.
fn face_field(face: &FaceGeometry, markers: &[usize], rng: &mut impl Rng) -> Vec<f64> {
    let mut field = vec![0.0; face.markers.len() * 3];
    let affine: Vec<f64> = (0..12).map(|_| rng.random_range(-1.0..1.0)).collect();
    for &i in markers {
        let c = face.markers[i].canonical;
        for a in 0..3 {
            let row = &affine[a * 4..a * 4 + 4];
            field[i * 3 + a] =
                0.5 * row[0] + (row[1] * c[0] + row[2] * c[1] + row[3] * c[2]) / 100.0;
        }
    }
    for _ in 0..SPREAD_BUMPS {
        let centre = face.markers[markers[rng.random_range(0..markers.len())]].canonical;
        let radius: f64 = rng.random_range(15.0..35.0);
        let (theta, phi) = (
            rng.random_range(0.0..2.0 * PI),
            rng.random_range(-1.0f64..1.0),
        );
        let r = (1.0 - phi * phi).sqrt();
        let dir = [r * theta.cos(), r * theta.sin(), phi];
        for &i in markers {
            let c = face.markers[i].canonical;
            let d2 = (c[0] - centre[0]).powi(2) + (c[1] - centre[1]).powi(2);
            let w = (-d2 / (2.0 * radius * radius)).exp();
            for a in 0..3 {
                field[i * 3 + a] += w * dir[a];
            }
        }
    }
    remove_rigid(face, markers, &mut field);
    let ss: f64 = markers
        .iter()
        .map(|&i| (0..3).map(|a| field[i * 3 + a].powi(2)).sum::<f64>())
        .sum();
    let rms = (ss / markers.len().max(1) as f64).sqrt();
    if rms > 0.0 {
        for v in &mut field {
            *v *= SPREAD_FIELD_MM / rms;
        }
    }
    field
}

/// Removes from `field` its least-squares rigid part over `markers` (a translation and a small
/// rotation about their centroid): an emotion moves the face, not the head, and a rigid part
/// would be taken for head motion by any stabilisation.
///
/// About the centroid the two parts separate: the translation is the mean displacement, and the
/// rotation `ω` solves `(Σ |r|² I − r rᵀ) ω = Σ r × (f − t)`.
fn remove_rigid(face: &FaceGeometry, markers: &[usize], field: &mut [f64]) {
    let n = markers.len().max(1) as f64;
    let (mut centre, mut t) = ([0.0; 3], [0.0; 3]);
    for &i in markers {
        for a in 0..3 {
            centre[a] += face.markers[i].canonical[a] / n;
            t[a] += field[i * 3 + a] / n;
        }
    }
    let arm = |i: usize| -> [f64; 3] {
        std::array::from_fn(|a| face.markers[i].canonical[a] - centre[a])
    };
    let mut inertia = [[0.0; 3]; 3];
    let mut torque = [0.0; 3];
    for &i in markers {
        let r = arm(i);
        let f: [f64; 3] = std::array::from_fn(|a| field[i * 3 + a] - t[a]);
        let rr = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
        for j in 0..3 {
            for k in 0..3 {
                inertia[j][k] += if j == k { rr } else { 0.0 } - r[j] * r[k];
            }
        }
        let c = cross(r, f);
        for j in 0..3 {
            torque[j] += c[j];
        }
    }
    let omega = solve3(inertia, torque).unwrap_or([0.0; 3]);
    for &i in markers {
        let spin = cross(omega, arm(i));
        for a in 0..3 {
            field[i * 3 + a] -= t[a] + spin[a];
        }
    }
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `m x = y` by Cramer's rule; `None` for a singular `m`.
fn solve3(m: [[f64; 3]; 3], y: [f64; 3]) -> Option<[f64; 3]> {
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(m);
    if d.abs() < 1e-12 {
        return None;
    }
    Some(std::array::from_fn(|c| {
        let mut mc = m;
        for r in 0..3 {
            mc[r][c] = y[r];
        }
        det(mc) / d
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(list: &[&str]) -> Vec<String> {
        list.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn knobs_are_checked_against_the_session() {
        let emotions = names(&["neutral", "happy", "angry"]);
        let ok = Variation {
            take_intensity: 0.4,
            takes: vec!["angry=3".parse().expect("parses")],
            speech_rate: vec!["happy=1.2".parse().expect("parses")],
            ..Variation::default()
        };
        assert!(ok.validate(&emotions, 8).is_ok());
        assert_eq!(ok.rate_of("happy"), 1.2);
        assert_eq!(ok.rate_of("angry"), 1.0);
        assert_eq!(ok.takes_of("angry"), Some(3));
        let bad = |v: Variation| v.validate(&emotions, 8).is_err();
        assert!(bad(Variation {
            takes: vec!["angry=9".parse().expect("parses")],
            ..Variation::default()
        }));
        assert!(bad(Variation {
            takes: vec!["angry=2.5".parse().expect("parses")],
            ..Variation::default()
        }));
        assert!(bad(Variation {
            speech_rate: vec!["calm=1.1".parse().expect("parses")],
            ..Variation::default()
        }));
        assert!(bad(Variation {
            take_intensity: f64::NAN,
            ..Variation::default()
        }));
        assert!("angry".parse::<NameValue>().is_err());
        assert!("angry=x".parse::<NameValue>().is_err());
    }

    #[test]
    fn a_subset_of_sentences_has_the_count_asked_for_and_depends_on_the_seed() {
        let a = spoken_in(1, "angry", Some(3), 8);
        assert_eq!(a.iter().filter(|&&s| s).count(), 3);
        assert_eq!(spoken_in(1, "angry", None, 8), vec![true; 8]);
        let draws: Vec<Vec<bool>> = (0..6).map(|s| spoken_in(s, "angry", Some(3), 8)).collect();
        assert!(
            draws.iter().any(|d| *d != a),
            "the seed picks the sentences"
        );
    }

    #[test]
    fn spread_effects_move_every_face_region_and_no_head_marker() {
        let face = FaceGeometry::standard();
        let layout = SourceLayout::new(2).expect("in range");
        let base = super::super::mixing::mixing_matrix(&face, false, layout);
        let mut spread = base.clone();
        add_spread_effects(&mut spread, &face, layout, 4, 1.0);
        let count = layout.count();
        for region in Region::ALL {
            let moved = face.indices(region).iter().any(|&i| {
                (0..3).any(|a| {
                    let at = (i * 3 + a) * count + layout.emotion(1);
                    (spread[at] - base[at]).abs() > 0.05
                })
            });
            assert_eq!(moved, region != Region::HeadReference, "{region:?}");
        }
    }
}
