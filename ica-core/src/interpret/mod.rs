//! Interpretation of the independent components (section 4 of the method): the emotion distance
//! of paired takes, the region metrics, and the labelling rule.
//!
//! Component series are frames x m, row-major `f64`.
//!
//! - [`emotion_distance`]: for pairs of takes with the same sentence and different emotions, align
//!   each pair by DTW and take the RMS difference of every component over all aligned samples
//!   (`d_emotion,j`, section 4.2).
//! - [`region_distance`]: `d_region,i = d(x_{E∪{i}}, x_all) − d(x_E, x_all)` on one region's
//!   markers (Eq. 3–4), computed exactly from the region's Gram matrix `M_Rᵀ M_R`, so no marker
//!   motion is reconstructed.
//! - Each metric is also an accumulator fed one pair or one take at a time
//!   ([`EmotionDistanceAcc`], [`LevelDistanceAcc`], [`ComponentMoments`]), so a session of hours
//!   can be measured holding one sentence's takes; the whole-slice functions above are those
//!   accumulators run over every input. [`ComponentMoments`] keeps the second moments of the
//!   components, from which the region metric of any region and any emotion set follows, so
//!   the emotion set need not be known while the takes stream past.
//! - [`label`]: roles from the metrics, with the thresholds in [`LabelRules`].

mod anova;
mod basis;
mod distance;
mod effect;

pub use basis::{emotion_basis, AxisTest, BasisTake, EmotionBasis};
pub use distance::{
    aligned_offset, emotion_distance, level_distance, region_distance, series_means, AlignedPair,
    ComponentMoments, EmotionDistanceAcc, LevelDistanceAcc,
};
pub use effect::{
    emotion_effects, emotion_subspace, f_upper_tail, EmotionEffect, TakeMeans, EMOTION_ALPHA,
};

use serde::{Deserialize, Serialize};

use crate::dtw::DtwError;
use crate::model::Role;

/// Why the metrics could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InterpretError {
    /// A series is not a whole number of m-component frames.
    #[error("component series of {len} values is not a whole number of {m}-component frames")]
    BadSeries {
        /// Values in the series.
        len: usize,
        /// Components.
        m: usize,
    },
    /// A region holds a marker outside the model.
    #[error("region marker {marker} out of range for {markers} markers")]
    BadMarker {
        /// The marker index.
        marker: usize,
        /// Markers in the model.
        markers: usize,
    },
    /// Moments of some number of components asked about a model of another.
    #[error("moments of {expected} components, model has {got}")]
    ComponentCountMismatch {
        /// Components in the moments.
        expected: usize,
        /// Components in the model.
        got: usize,
    },
    /// A region holds no marker.
    #[error("region has no markers")]
    EmptyRegion,
    /// Alignment failed.
    #[error("dtw")]
    Dtw(#[from] DtwError),
}

/// `d_emotion` and what it was computed from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EmotionDistance {
    /// `d_emotion,j` per component.
    pub per_component: Vec<f64>,
    /// Aligned samples per pair (`q_i`).
    pub aligned_samples: Vec<usize>,
}

/// Thresholds of the labelling rule. Defaults are the documented values.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LabelRules {
    /// A component is emotion when its emotion distance is at least this multiple of the
    /// median over components (a clear peak). Default 3.0.
    pub emotion_peak_ratio: f64,
    /// …and at least this share of the largest (several peaks allowed). Default 0.5.
    pub emotion_share_of_max: f64,
    /// A component takes a region's role when that region holds at least this share of its
    /// `|d_region|` summed over the role regions. Default 0.5.
    pub region_share_of_component: f64,
    /// …and its `|d_region|` there is at least this share of the region's largest among the
    /// non-emotion components, so that near-silent (noise) components stay `other`.
    /// Default 0.02.
    pub region_floor_of_max: f64,
}

impl Default for LabelRules {
    fn default() -> LabelRules {
        LabelRules {
            emotion_peak_ratio: 3.0,
            emotion_share_of_max: 0.5,
            region_share_of_component: 0.5,
            region_floor_of_max: 0.02,
        }
    }
}

/// The emotion component(s): the clear peaks of an emotion distance (`d_level` or `d_emotion`)
/// under `rules`.
pub fn emotion_components(d_emotion: &[f64], rules: &LabelRules) -> Vec<usize> {
    let mut sorted = d_emotion.to_vec();
    sorted.sort_by(f64::total_cmp);
    let median = match sorted.len() {
        0 => return Vec::new(),
        n if n % 2 == 1 => sorted[n / 2],
        n => 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]),
    };
    let max = sorted[sorted.len() - 1];
    (0..d_emotion.len())
        .filter(|&j| {
            let d = d_emotion[j];
            d > 0.0
                && d >= rules.emotion_peak_ratio * median
                && d >= rules.emotion_share_of_max * max
        })
        .collect()
}

/// Roles from the metrics. `regions` holds `(role, d_region per component)` for the regions that
/// decide roles (mouth → speech, eyebrows, eyelids). A non-emotion component takes the role of
/// the region holding at least `rules.region_share_of_component` of its summed `|d_region|`,
/// provided it moves that region by at least `rules.region_floor_of_max` of the region's
/// largest; otherwise it is `Other`. The share is per component, so a weak component that acts
/// only on the mouth is still speech.
pub fn label(
    m: usize,
    emotion: &[usize],
    regions: &[(Role, &[f64])],
    rules: &LabelRules,
) -> Vec<Role> {
    let maxima: Vec<f64> = regions
        .iter()
        .map(|(_, d)| {
            (0..m)
                .filter(|i| !emotion.contains(i))
                .map(|i| d[i].abs())
                .fold(0.0, f64::max)
        })
        .collect();
    (0..m)
        .map(|i| {
            if emotion.contains(&i) {
                return Role::Emotion;
            }
            let total: f64 = regions.iter().map(|(_, d)| d[i].abs()).sum();
            let best = regions
                .iter()
                .zip(&maxima)
                .max_by(|a, b| a.0 .1[i].abs().total_cmp(&b.0 .1[i].abs()));
            match best {
                Some(((role, d), &max))
                    if total > 0.0
                        && d[i].abs() >= rules.region_share_of_component * total
                        && d[i].abs() >= rules.region_floor_of_max * max =>
                {
                    *role
                }
                _ => Role::Other,
            }
        })
        .collect()
}

/// Mean of component `k` over a set of takes (frames x m series): an emotion level.
pub fn component_mean(takes: &[&[f64]], m: usize, k: usize) -> Option<f64> {
    let (mut sum, mut n) = (0.0, 0usize);
    for series in takes {
        for row in series.chunks_exact(m) {
            sum += row[k];
            n += 1;
        }
    }
    (n > 0).then(|| sum / n as f64)
}

#[cfg(test)]
mod tests;
