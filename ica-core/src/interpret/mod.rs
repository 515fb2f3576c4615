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
//! - [`label`]: roles from the metrics, with the thresholds in [`LabelRules`].

mod effect;

pub use effect::{
    emotion_effects, emotion_subspace, f_upper_tail, EmotionEffect, TakeMeans, EMOTION_ALPHA,
};

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use crate::dtw::{self, DtwError};
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

fn frames_of(series: &[f64], m: usize) -> Result<usize, InterpretError> {
    if m == 0 || series.len() % m != 0 {
        return Err(InterpretError::BadSeries {
            len: series.len(),
            m,
        });
    }
    Ok(series.len() / m)
}

/// `d_emotion,j` over pairs of component series of the same sentence in two emotions.
///
/// `band` is the DTW Sakoe-Chiba radius in frames (`None`: unconstrained).
///
/// # Errors
/// A series of the wrong shape, or an alignment failure (empty or non-finite series).
pub fn emotion_distance(
    pairs: &[(&[f64], &[f64])],
    m: usize,
    band: Option<usize>,
) -> Result<EmotionDistance, InterpretError> {
    let mut sum = vec![0.0; m];
    let mut aligned_samples = Vec::with_capacity(pairs.len());
    for (a, b) in pairs {
        // Shapes checked first, for a typed error naming the series.
        frames_of(a, m)?;
        frames_of(b, m)?;
        let alignment = dtw::align(&dtw::demeaned(a, m), &dtw::demeaned(b, m), m, band)?;
        for &(i, j) in &alignment.path {
            for (k, acc) in sum.iter_mut().enumerate() {
                let d = a[i * m + k] - b[j * m + k];
                *acc += d * d;
            }
        }
        aligned_samples.push(alignment.path.len());
    }
    let total: usize = aligned_samples.iter().sum();
    let per_component = sum
        .iter()
        .map(|s| (s / total.max(1) as f64).sqrt())
        .collect();
    Ok(EmotionDistance {
        per_component,
        aligned_samples,
    })
}

/// `d_level,j`: the RMS over pairs of the difference of component `j`'s take means.
///
/// Emotion moves a component's level for a whole take, while speech, blinks and noise average
/// out over a take of the same sentence. Unlike `d_emotion`, this does not grow with components
/// that are noise (independent between takes, so their aligned RMS difference is about √2 for a
/// unit-variance component), which makes its peak the robust label of emotion when the variance
/// target keeps many components.
///
/// # Errors
/// A series of the wrong shape.
pub fn level_distance(pairs: &[(&[f64], &[f64])], m: usize) -> Result<Vec<f64>, InterpretError> {
    let mut sum = vec![0.0; m];
    for (a, b) in pairs {
        let (na, nb) = (frames_of(a, m)?, frames_of(b, m)?);
        for (k, acc) in sum.iter_mut().enumerate() {
            let ma = a.iter().skip(k).step_by(m).sum::<f64>() / na.max(1) as f64;
            let mb = b.iter().skip(k).step_by(m).sum::<f64>() / nb.max(1) as f64;
            *acc += (ma - mb) * (ma - mb);
        }
    }
    Ok(sum
        .iter()
        .map(|s| (s / pairs.len().max(1) as f64).sqrt())
        .collect())
}

/// `d_region,i` for every component `i` (Eq. 4), given the emotion subset `emotion` (`E`, may be
/// empty) and the region's marker indices.
///
/// The distance of Eq. 3 averages the squared 3-D marker distance over the region's `r` markers
/// and all frames of all takes, then takes the square root.
///
/// # Errors
/// Bad series shape, an empty region or a marker outside the model.
pub fn region_distance(
    mixing: &DMatrix<f64>,
    takes: &[&[f64]],
    region: &[usize],
    emotion: &[usize],
) -> Result<Vec<f64>, InterpretError> {
    let m = mixing.ncols();
    let markers = mixing.nrows() / 3;
    if region.is_empty() {
        return Err(InterpretError::EmptyRegion);
    }
    if let Some(&marker) = region.iter().find(|&&r| r >= markers) {
        return Err(InterpretError::BadMarker { marker, markers });
    }
    // Gram matrix of the region's rows: ||M_R w||² = wᵀ G w.
    let mut gram = DMatrix::<f64>::zeros(m, m);
    for &r in region {
        for row in r * 3..r * 3 + 3 {
            let line = mixing.row(row);
            gram += line.transpose() * line;
        }
    }
    let mut base = 0.0; // Σ_t ||v_t||², v_t = M_R (u_t with E zeroed)
    let mut cross = vec![0.0; m]; // Σ_t u_i(t) (G w_t)_i
    let mut power = vec![0.0; m]; // Σ_t u_i(t)²
    let mut q = 0usize;
    let mut w = nalgebra::DVector::<f64>::zeros(m);
    let mut gw = nalgebra::DVector::<f64>::zeros(m);
    for series in takes {
        frames_of(series, m)?;
        for row in series.chunks_exact(m) {
            w.copy_from_slice(row);
            for &e in emotion {
                w[e] = 0.0;
            }
            gw.gemv(1.0, &gram, &w, 0.0);
            base += w.dot(&gw);
            for i in 0..m {
                if !emotion.contains(&i) {
                    cross[i] += row[i] * gw[i];
                    power[i] += row[i] * row[i];
                }
            }
            q += 1;
        }
    }
    let norm = (q.max(1) * region.len()) as f64;
    let d_e = (base / norm).max(0.0).sqrt();
    Ok((0..m)
        .map(|i| {
            if emotion.contains(&i) {
                return 0.0;
            }
            let with_i = base - 2.0 * cross[i] + gram[(i, i)] * power[i];
            (with_i / norm).max(0.0).sqrt() - d_e
        })
        .collect())
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
