//! The emotion space of a model: the components whose levels differ between emotions, and each
//! named emotion's point (level vector) in them.
//!
//! The paper's *Translate* moves one emotion component between two levels. Real emotions do not
//! lie on one line (happy lifts the mouth corners, angry knits the brows, sad does some of
//! both), so a model holds an emotion space and every emotion is a point there: its level on
//! each axis, with the spread across takes kept.
//!
//! The axes are weights on the components ([`EmotionLevels::axes`], with the components each
//! one moves, [`EmotionLevels::moves`]), fitted over every component so that the space does not
//! depend on how ICA split the emotion between components (issue 34,
//! [`crate::interpret::emotion_basis`]). Models without axes use their emotion components
//! themselves as axes (`k` components, `k` dimensions); one emotion component is the special
//! case `k = 1`, and models written before spaces existed (one `component` with scalar
//! `levels`) read as exactly that.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// One emotion's point in the emotion space.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EmotionPoint {
    /// Level of each emotion component (the mean over this emotion's takes), in the order of
    /// [`EmotionLevels::components`].
    pub level: Vec<f64>,
    /// Standard deviation of each coordinate across this emotion's takes (0 with one take).
    #[serde(default)]
    pub spread: Vec<f64>,
    /// Takes the point was measured on.
    #[serde(default)]
    pub takes: usize,
}

/// The emotion space of a model. See the module docs.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct EmotionLevels {
    /// The main emotion component (the strongest emotion effect), once known. Kept for tools
    /// that read one component.
    pub component: Option<usize>,
    /// Level of the main component per emotion name, ordered by name.
    pub levels: BTreeMap<String, f64>,
    /// Every emotion component, ascending (empty in models written before emotion spaces:
    /// then the space is `component` alone).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub components: Vec<usize>,
    /// Each emotion's point over `components`.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub points: BTreeMap<String, EmotionPoint>,
    /// Per axis: the share of a take's deviation from its emotion's point that belongs to its
    /// sentence and so persists in another emotion (0..1; empty: 0).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub persistence: Vec<f64>,
    /// The axes of the space as weights on the components: a take's coordinate on axis `j` is
    /// `axes[j] · u` (one row of one weight per component). Empty: the axes are `components`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub axes: Vec<Vec<f64>>,
    /// The components a move of one unit along each axis changes (one row per axis, one value
    /// per component), with `axes · movesᵀ = I`. Empty exactly when `axes` is.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub moves: Vec<Vec<f64>>,
    /// How the space was found and whether its components alone would be a sound set of axes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub conditioning: Option<Conditioning>,
}

/// Whether the emotion components, one per axis, would make a sound space, and what was done
/// (issue 34). ICA may split an emotion direction between components, or blend two directions
/// into one: the components' levels then move together, or a restart finds other components.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Conditioning {
    /// The emotion components that would be the axes: those whose take levels the emotions
    /// explain (the per-component F test, most of their level variance).
    pub components: Vec<usize>,
    /// Dimensions the session shows (the test over all components).
    pub dims: usize,
    /// Condition number of the emotions' points on `components` (centred): large when two
    /// components' levels move together.
    pub condition: f64,
    /// Emotion components the other training restarts did not find again, with their best
    /// match (below 0.9).
    #[serde(default)]
    pub unstable: Vec<(usize, f64)>,
    /// Pairs of emotion components whose take levels correlate by |r| ≥ 0.9, with r.
    #[serde(default)]
    pub collinear: Vec<(usize, usize, f64)>,
    /// Whether the components alone would be an ill-conditioned space.
    pub ill_conditioned: bool,
    /// What the edits do, in words.
    pub note: String,
}

/// A fitted emotion space for [`crate::IcaModel::set_fitted_space`].
#[derive(Debug, Clone, PartialEq)]
pub struct FittedSpace {
    /// Axes as weights on the components ([`EmotionLevels::axes`]).
    pub axes: Vec<Vec<f64>>,
    /// Moves along the axes ([`EmotionLevels::moves`]).
    pub moves: Vec<Vec<f64>>,
    /// Each emotion's point over the axes.
    pub points: BTreeMap<String, EmotionPoint>,
    /// Each axis's persistence.
    pub persistence: Vec<f64>,
    /// How it was found.
    pub conditioning: Conditioning,
}

/// Why a blend or a point could not be formed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BlendError {
    /// The model has no emotion component.
    #[error("the model has no emotion component")]
    NoEmotion,
    /// A name the model does not know.
    #[error("unknown emotion {name:?} (the model knows {known})")]
    UnknownEmotion {
        /// The name given.
        name: String,
        /// The names the model knows, comma separated.
        known: String,
    },
    /// A weight that is negative, NaN or infinite, or weights that sum to zero.
    #[error(
        "blend weight {weight} for {name:?}: weights must be finite, at least 0, and not all 0"
    )]
    BadWeight {
        /// The emotion.
        name: String,
        /// The weight.
        weight: f64,
    },
}

impl EmotionLevels {
    /// The emotion components: `components`, or the single `component` of an older model.
    pub fn space_components(&self) -> Vec<usize> {
        if self.components.is_empty() {
            self.component.into_iter().collect()
        } else {
            self.components.clone()
        }
    }

    /// Dimensions of the space (0 when not analysed).
    pub fn dims(&self) -> usize {
        if self.axes.is_empty() {
            self.space_components().len()
        } else {
            self.axes.len()
        }
    }

    /// Names of the axes, in order: `e1`, `e2`, ... for fitted axes, `c0`, `c3`, ... for
    /// emotion components.
    pub fn axis_names(&self) -> Vec<String> {
        if self.axes.is_empty() {
            self.space_components()
                .iter()
                .map(|k| format!("c{k}"))
                .collect()
        } else {
            (1..=self.axes.len()).map(|j| format!("e{j}")).collect()
        }
    }

    /// The axes as weights on `m` components and the moves along them, each `dims x m`
    /// row-major: the fitted axes, or one emotion component per axis. Components outside the
    /// model are left out (an invalid model is refused at load; this keeps callers safe).
    pub fn axis_matrices(&self, m: usize) -> (Vec<f64>, Vec<f64>) {
        if !self.axes.is_empty() {
            let flat = |rows: &[Vec<f64>]| -> Vec<f64> {
                rows.iter()
                    .flat_map(|r| (0..m).map(|k| r.get(k).copied().unwrap_or(0.0)))
                    .collect()
            };
            return (flat(&self.axes), flat(&self.moves));
        }
        let space = self.space_components();
        let mut select = vec![0.0; space.len() * m];
        for (j, &k) in space.iter().enumerate() {
            if k < m {
                select[j * m + k] = 1.0;
            }
        }
        (select.clone(), select)
    }

    /// Emotion names with a point, in name order.
    pub fn names(&self) -> Vec<String> {
        if self.points.is_empty() {
            self.levels.keys().cloned().collect()
        } else {
            self.points.keys().cloned().collect()
        }
    }

    /// The point of `name` over [`EmotionLevels::space_components`].
    pub fn point(&self, name: &str) -> Option<Vec<f64>> {
        if self.points.is_empty() {
            return self.component.and(self.levels.get(name).map(|&l| vec![l]));
        }
        self.points.get(name).map(|p| p.level.clone())
    }

    /// The blended point `Σ wᵢ pᵢ / Σ wᵢ` of named emotions, e.g. `sad 0.5, angry 0.5`.
    ///
    /// # Errors
    /// [`BlendError`] for no emotion space, an unknown name or a bad weight.
    pub fn blend(&self, weights: &[(&str, f64)]) -> Result<Vec<f64>, BlendError> {
        if self.dims() == 0 {
            return Err(BlendError::NoEmotion);
        }
        let total: f64 = weights.iter().map(|w| w.1).sum();
        let mut out = vec![0.0; self.dims()];
        for &(name, weight) in weights {
            if !(weight.is_finite() && weight >= 0.0 && total > 0.0) {
                return Err(BlendError::BadWeight {
                    name: name.to_string(),
                    weight,
                });
            }
            let point = self.point(name).ok_or_else(|| BlendError::UnknownEmotion {
                name: name.to_string(),
                known: self.names().join(", "),
            })?;
            for (o, p) in out.iter_mut().zip(point) {
                *o += weight / total * p;
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests;
