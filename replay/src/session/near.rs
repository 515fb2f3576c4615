//! What a take has instead of the markers a region names: the hint that ends
//! [`super::SessionError::UnknownLabel`] and [`super::SessionError::EmptyRegion`].

use globset::{GlobBuilder, GlobMatcher};

/// Labels shown at most by [`near_labels`].
const NEAR_SHOWN: usize = 6;

/// For a region that matched nothing: the labels its `patterns` match ignoring case (labels
/// are case-sensitive: `ROOT-*` does not match `root-1`), or else the first of the take's
/// labels, so the message shows what to write.
pub(super) fn near_labels<S: AsRef<str>>(labels: &[S], patterns: &[String]) -> String {
    let folded: Vec<GlobMatcher> = patterns
        .iter()
        .filter_map(|p| {
            GlobBuilder::new(p)
                .case_insensitive(true)
                .build()
                .ok()
                .map(|g| g.compile_matcher())
        })
        .collect();
    let near: Vec<&str> = labels
        .iter()
        .map(AsRef::as_ref)
        .filter(|l| folded.iter().any(|m| m.is_match(l)))
        .collect();
    let list = |shown: &[&str]| {
        let mut text = shown
            .iter()
            .take(NEAR_SHOWN)
            .map(|l| format!("{l:?}"))
            .collect::<Vec<_>>()
            .join(", ");
        if shown.len() > NEAR_SHOWN {
            text.push_str(&format!(" and {} more", shown.len() - NEAR_SHOWN));
        }
        text
    };
    if near.is_empty() {
        let all: Vec<&str> = labels.iter().map(AsRef::as_ref).collect();
        format!("; its markers are {}", list(&all))
    } else {
        format!(
            "; labels are case-sensitive, and the take has {}",
            list(&near)
        )
    }
}
