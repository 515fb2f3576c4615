//! The script of a calibration session: which sentences, in which emotions, in which order.
//! The built-in default is [`HARVARD`] (public-domain, phonetically balanced sentences, IEEE
//! 1969) in neutral, happy, sad and angry; a script file says the same in TOML:
//!
//! ```toml
//! emotions = ["neutral", "happy", "sad", "angry"]
//! [[sentence]]
//! text = "The birch canoe slid on the smooth planks."
//! seconds = [1.5, 12.0]   # optional: the take's accepted length
//! ```
//!
//! Takes come sentence by sentence, and each sentence's emotions start one later than the
//! previous sentence's ([`Script::plan`]: a Latin square), so no emotion always comes first
//! or last, when the performer is fresh or tired.

use serde::{Deserialize, Serialize};

/// The default number of sentences each emotion is recorded in: the fewest with which a
/// session trains and analyses to the generator's roles and emotion space (see
/// `docs/session.md`). `analyze` advises recording at least this many.
pub const DEFAULT_SENTENCES: usize = crate::offline::analysis::MIN_SENTENCES_PER_EMOTION;

/// The emotions of the default script.
pub const DEFAULT_EMOTIONS: [&str; 4] = ["neutral", "happy", "sad", "angry"];

/// Harvard sentences, lists 1 and 2 (IEEE Recommended Practice for Speech Quality
/// Measurements, 1969; public domain): phonetically balanced, about 2-3 s each spoken.
pub const HARVARD: [&str; 20] = [
    "The birch canoe slid on the smooth planks.",
    "Glue the sheet to the dark blue background.",
    "It's easy to tell the depth of a well.",
    "These days a chicken leg is a rare dish.",
    "Rice is often served in round bowls.",
    "The juice of lemons makes fine punch.",
    "The box was thrown beside the parked truck.",
    "The hogs were fed chopped corn and garbage.",
    "Four hours of steady work faced us.",
    "A large size in stockings is hard to sell.",
    "The boy was there when the sun rose.",
    "A rod is used to catch pink salmon.",
    "The source of the huge river is the clear spring.",
    "Kick the ball straight and follow through.",
    "Help the woman get back to her feet.",
    "A pot of tea helps to pass the evening.",
    "Smoky fires lack flame and heat.",
    "The soft cushion broke the man's fall.",
    "The salt breeze came across from the sea.",
    "The girl at the booth sold fifty bonds.",
];

/// Seconds a spoken word takes at a calm pace, for a sentence's expected length.
const SECONDS_PER_WORD: f64 = 0.4;
/// A take may be this much shorter than expected ...
const SHORTEST_SHARE: f64 = 0.35;
/// ... or this many times longer (pauses, a slow sad reading).
const LONGEST_FACTOR: f64 = 4.0;
/// No take is accepted shorter than this, however short the sentence.
const SHORTEST_SECONDS: f64 = 1.0;

/// One sentence of a script.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sentence {
    /// What the performer says.
    pub text: String,
    /// The accepted length of a take, seconds `[shortest, longest]`; from the word count
    /// when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seconds: Option<[f64; 2]>,
}

impl Sentence {
    /// The accepted length of a take of it, seconds.
    pub fn seconds_range(&self) -> (f64, f64) {
        if let Some([lo, hi]) = self.seconds {
            return (lo, hi);
        }
        let words = self.text.split_whitespace().count().max(1) as f64;
        let expected = words * SECONDS_PER_WORD;
        (
            (expected * SHORTEST_SHARE).max(SHORTEST_SECONDS),
            (expected * LONGEST_FACTOR).max(SHORTEST_SECONDS * 4.0),
        )
    }
}

/// A session's script.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Script {
    /// The emotions each sentence is spoken in.
    pub emotions: Vec<String>,
    /// The sentences.
    #[serde(rename = "sentence")]
    pub sentences: Vec<Sentence>,
}

/// One take the script asks for.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Prompt {
    /// The sentence, from 0 in the script.
    pub sentence: usize,
    /// The emotion.
    pub emotion: String,
}

/// A script that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum ScriptError {
    /// Not TOML of the script's shape.
    #[error("not a session script: {0} (expected `emotions = [...]` and [[sentence]] tables with `text`)")]
    Toml(#[from] toml::de::Error),
    /// Fewer than two emotions.
    #[error("a script needs at least two emotions, got {0}")]
    FewEmotions(usize),
    /// No sentence.
    #[error("a script needs at least one [[sentence]]")]
    NoSentences,
    /// An emotion name that cannot be a file name part.
    #[error("emotion {0:?}: use letters, digits, '-' or '_' (it names the take files)")]
    BadEmotion(String),
    /// The same emotion twice.
    #[error("emotion {0:?} is listed twice")]
    RepeatedEmotion(String),
    /// An empty sentence.
    #[error("sentence {0} has no text")]
    EmptySentence(usize),
    /// A length range that is not `0 < shortest < longest`.
    #[error("sentence {0}: seconds must be [shortest, longest] with 0 < shortest < longest")]
    BadSeconds(usize),
    /// More sentences than take names can number.
    #[error("a script holds at most 99 sentences, got {0}")]
    TooManySentences(usize),
}

impl Script {
    /// The default script: the first `sentences` Harvard sentences (at most 20) in
    /// [`DEFAULT_EMOTIONS`].
    pub fn harvard(sentences: usize) -> Script {
        Script {
            emotions: DEFAULT_EMOTIONS.map(String::from).to_vec(),
            sentences: HARVARD
                .iter()
                .take(sentences.clamp(1, HARVARD.len()))
                .map(|t| Sentence {
                    text: (*t).to_string(),
                    seconds: None,
                })
                .collect(),
        }
    }

    /// Parses and checks a script.
    ///
    /// # Errors
    /// Malformed TOML or a broken rule of [`Script::validate`].
    pub fn parse(text: &str) -> Result<Script, ScriptError> {
        let script: Script = toml::from_str(text)?;
        script.validate()?;
        Ok(script)
    }

    /// The script as TOML (kept in the session's folder, so `--resume` follows the same one).
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("a script always serialises")
    }

    /// Checks the emotions, the sentences and their lengths.
    ///
    /// # Errors
    /// The first broken rule.
    pub fn validate(&self) -> Result<(), ScriptError> {
        if self.emotions.len() < 2 {
            return Err(ScriptError::FewEmotions(self.emotions.len()));
        }
        for (i, e) in self.emotions.iter().enumerate() {
            let ok = !e.is_empty()
                && e.chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
            if !ok {
                return Err(ScriptError::BadEmotion(e.clone()));
            }
            if self.emotions[..i].contains(e) {
                return Err(ScriptError::RepeatedEmotion(e.clone()));
            }
        }
        if self.sentences.is_empty() {
            return Err(ScriptError::NoSentences);
        }
        if self.sentences.len() > 99 {
            return Err(ScriptError::TooManySentences(self.sentences.len()));
        }
        for (i, s) in self.sentences.iter().enumerate() {
            if s.text.trim().is_empty() {
                return Err(ScriptError::EmptySentence(i + 1));
            }
            if let Some([lo, hi]) = s.seconds {
                if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo < hi) {
                    return Err(ScriptError::BadSeconds(i + 1));
                }
            }
        }
        Ok(())
    }

    /// The takes in recording order: sentence by sentence, sentence `k`'s emotions rotated by
    /// `k` places.
    pub fn plan(&self) -> Vec<Prompt> {
        let n = self.emotions.len();
        (0..self.sentences.len())
            .flat_map(|k| {
                (0..n).map(move |j| Prompt {
                    sentence: k,
                    emotion: self.emotions[(j + k) % n].clone(),
                })
            })
            .collect()
    }
}

impl Prompt {
    /// The take's file name: `s<NN>_<emotion>.<ext>` (NN the sentence's number, from 1).
    pub fn file_name(&self, ext: &str) -> String {
        format!("s{:02}_{}.{ext}", self.sentence + 1, self.emotion)
    }

    /// The sentence id the manifest gives it: `s<NN>`.
    pub fn sentence_id(&self) -> String {
        format!("s{:02}", self.sentence + 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_plan_varies_the_emotion_order_per_sentence_and_covers_every_pair() {
        let script = Script::harvard(4);
        let plan = script.plan();
        assert_eq!(plan.len(), 16);
        for k in 0..4 {
            for e in &script.emotions {
                assert_eq!(
                    plan.iter()
                        .filter(|p| p.sentence == k && &p.emotion == e)
                        .count(),
                    1
                );
            }
        }
        // Each emotion comes first once in four sentences, and last once.
        for e in &script.emotions {
            let first = (0..4).filter(|k| &plan[k * 4].emotion == e).count();
            let last = (0..4).filter(|k| &plan[k * 4 + 3].emotion == e).count();
            assert_eq!((first, last), (1, 1), "{e}");
        }
    }

    #[test]
    fn a_script_file_parses_and_names_what_is_wrong() {
        let s = Script::parse(
            "emotions = [\"neutral\", \"happy\"]\n[[sentence]]\ntext = \"Hi there.\"\nseconds = [1.0, 5.0]\n",
        )
        .expect("valid");
        assert_eq!(s.sentences[0].seconds_range(), (1.0, 5.0));
        assert_eq!(Script::parse(&s.to_toml()).expect("round trip"), s);
        let one = Script::parse("emotions = [\"neutral\"]\n[[sentence]]\ntext = \"a\"\n");
        assert!(matches!(one, Err(ScriptError::FewEmotions(1))), "{one:?}");
        let path = Script::parse("emotions = [\"a/b\", \"c\"]\n[[sentence]]\ntext = \"a\"\n");
        assert!(matches!(path, Err(ScriptError::BadEmotion(_))), "{path:?}");
        let unknown = Script::parse("emotions = [\"a\", \"c\"]\nsentences = 3\n");
        assert!(matches!(unknown, Err(ScriptError::Toml(_))), "{unknown:?}");
    }

    #[test]
    fn a_harvard_sentence_expects_a_few_seconds() {
        let (lo, hi) = Script::harvard(1).sentences[0].seconds_range();
        assert!(lo <= 2.0 && hi >= 8.0, "{lo}..{hi}");
        assert_eq!(
            Prompt {
                sentence: 2,
                emotion: "sad".into()
            }
            .file_name("c3d"),
            "s03_sad.c3d"
        );
    }
}
