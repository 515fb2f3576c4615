//! What a session lacks, in words for the terminal and the report alike (issue 37): emotions
//! that cannot be told apart, components that nearly passed the emotion test, and how many
//! sentences per emotion to record.

use std::collections::{BTreeMap, BTreeSet};

use ica_core::interpret::EMOTION_ALPHA;
use serde::Serialize;

use super::space::{EmotionSpace, EMOTION_ROLE_SHARE};
use super::{TakeSummary, MIN_SENTENCES_PER_EMOTION};

/// A component whose levels differ between emotions by the uncorrected test (p below
/// [`EMOTION_ALPHA`]) and that the emotions mostly explain (share at least
/// [`EMOTION_ROLE_SHARE`]), but that missed the test corrected over all components: with
/// more takes it would most likely be an emotion component.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct NearMiss {
    /// Component index.
    pub component: usize,
    /// Share of its take-level variance the emotions explain.
    pub emotion_share: f64,
    /// p-value of its emotion test.
    pub p: f64,
    /// The corrected threshold it missed: [`EMOTION_ALPHA`] over the components tested.
    pub threshold: f64,
}

/// The components of `space` that nearly passed, strongest share first.
pub fn near_misses(space: &EmotionSpace) -> Vec<NearMiss> {
    let threshold = EMOTION_ALPHA / space.effects.len().max(1) as f64;
    let mut out: Vec<NearMiss> = space
        .effects
        .iter()
        .enumerate()
        .filter(|(k, e)| {
            !space.components.contains(k)
                && e.p < EMOTION_ALPHA
                && e.emotion_share >= EMOTION_ROLE_SHARE
        })
        .map(|(component, e)| NearMiss {
            component,
            emotion_share: e.emotion_share,
            p: e.p,
            threshold,
        })
        .collect();
    out.sort_by(|a, b| b.emotion_share.total_cmp(&a.emotion_share));
    out
}

/// The fewest sentences any emotion of `takes` was recorded with (0 without takes).
pub fn sentences_per_emotion(takes: &[TakeSummary]) -> usize {
    let mut by_emotion: BTreeMap<&str, BTreeSet<&str>> = BTreeMap::new();
    for t in takes {
        by_emotion
            .entry(t.emotion.as_str())
            .or_default()
            .insert(t.sentence.as_str());
    }
    by_emotion.values().map(BTreeSet::len).min().unwrap_or(0)
}

/// One line each: emotions that cannot be told apart, components that nearly passed, and the
/// advice to record more sentences when the session has fewer than
/// [`MIN_SENTENCES_PER_EMOTION`] in some emotion. Empty when the session lacks nothing.
pub fn lines(space: Option<&EmotionSpace>, near: &[NearMiss], sentences: usize) -> Vec<String> {
    let mut out = Vec::new();
    if let Some(space) = space {
        for i in &space.indistinct {
            out.push(format!(
                "{} and {} cannot be told apart: their levels are {:.3} apart, against a spread \
                 of {:.3} across takes; record more sentences in both, or merge them",
                i.a, i.b, i.distance, i.spread
            ));
        }
    }
    for n in near {
        out.push(format!(
            "c{} nearly passed the emotion test: emotion share {:.0} %, p = {:.2e} (needs p < \
             {:.1e}); more sentences per emotion would most likely make it an emotion component",
            n.component,
            100.0 * n.emotion_share,
            n.p,
            n.threshold
        ));
    }
    if sentences < MIN_SENTENCES_PER_EMOTION {
        out.push(format!(
            "record at least {MIN_SENTENCES_PER_EMOTION} sentences per emotion; you have \
             {sentences} (see docs/session.md)"
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn take(sentence: &str, emotion: &str) -> TakeSummary {
        TakeSummary {
            file: format!("{sentence}_{emotion}.c3d"),
            sentence: sentence.into(),
            emotion: emotion.into(),
            frames: 10,
            component_means: vec![],
        }
    }

    #[test]
    fn the_fewest_sentences_of_any_emotion_count() {
        let takes = [
            take("s1", "happy"),
            take("s2", "happy"),
            take("s3", "happy"),
            take("s1", "sad"),
            take("s1", "sad"),
        ];
        assert_eq!(sentences_per_emotion(&takes), 1);
        assert_eq!(sentences_per_emotion(&[]), 0);
    }

    #[test]
    fn a_small_session_is_told_how_many_sentences_to_record() {
        let l = lines(None, &[], 3);
        assert_eq!(
            l,
            [format!(
                "record at least {MIN_SENTENCES_PER_EMOTION} sentences per emotion; you have 3 \
                 (see docs/session.md)"
            )]
        );
        assert!(lines(None, &[], MIN_SENTENCES_PER_EMOTION).is_empty());
    }

    #[test]
    fn a_near_miss_names_its_share_and_p() {
        let near = [NearMiss {
            component: 4,
            emotion_share: 0.98,
            p: 3e-4,
            threshold: 1e-4,
        }];
        let l = lines(None, &near, MIN_SENTENCES_PER_EMOTION);
        assert!(l[0].starts_with("c4 nearly passed"), "{l:?}");
        assert!(l[0].contains("98 %") && l[0].contains("3.00e-4"), "{l:?}");
    }
}
