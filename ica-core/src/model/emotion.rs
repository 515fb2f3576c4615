//! The emotion space of a model: the components whose levels differ between emotions, and each
//! named emotion's point (level vector) in them.
//!
//! The paper's *Translate* moves one emotion component between two levels. Real emotions do not
//! lie on one line (happy lifts the mouth corners, angry knits the brows, sad does some of
//! both), so a model holds a subspace of `k` emotion components and every emotion is a point
//! there: the mean over its takes, with the spread across takes kept. One emotion component is
//! the special case `k = 1`, and models written before spaces existed (one `component` with
//! scalar `levels`) read as exactly that.

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
    /// Per emotion component: the share of a take's deviation from its emotion's point that
    /// belongs to its sentence and so persists in another emotion (0..1; empty: 0).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub persistence: Vec<f64>,
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
        self.space_components().len()
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

/// Where each emotion component should go to reach a goal point, frame by frame, allocation
/// free (f32, buffers sized at construction).
///
/// Moving a take to the goal's absolute levels is right for a component that carries emotion
/// alone, but wipes out a component whose level also depends on what is said (its sentence):
/// that part should persist. With the take's current levels `c`, its source point estimated as
/// `ŝ = Σ_e w_e p_e` (each emotion weighted by the Gaussian likelihood of `c` under that
/// emotion's spread), and each component's persistence `ρ` (its sentence share), the target is
/// `goal + ρ ⊙ (c − ŝ)`: the best linear guess of the same sentence spoken in the goal emotion.
#[derive(Debug, Clone)]
pub struct SpaceTarget {
    dims: usize,
    /// Emotion points, emotions x dims.
    points: Vec<f32>,
    /// 1 / pooled within-emotion variance, per dim.
    inv_var: Vec<f32>,
    persistence: Vec<f32>,
    weights: Vec<f32>,
}

impl SpaceTarget {
    /// The targeting of a model's emotion space.
    pub fn new(levels: &EmotionLevels) -> SpaceTarget {
        let dims = levels.dims();
        let names = levels.names();
        let points: Vec<f32> = names
            .iter()
            .flat_map(|n| levels.point(n).unwrap_or_else(|| vec![0.0; dims]))
            .map(|v| v as f32)
            .collect();
        let inv_var = (0..dims)
            .map(|j| {
                let spreads: Vec<f64> = levels
                    .points
                    .values()
                    .filter_map(|p| p.spread.get(j).copied())
                    .collect();
                let var = spreads.iter().map(|s| s * s).sum::<f64>() / spreads.len().max(1) as f64;
                (1.0 / var.max(1e-6)) as f32
            })
            .collect();
        let persistence = (0..dims)
            .map(|j| {
                levels
                    .persistence
                    .get(j)
                    .copied()
                    .unwrap_or(0.0)
                    .clamp(0.0, 1.0) as f32
            })
            .collect();
        SpaceTarget {
            dims,
            weights: vec![0.0; names.len()],
            points,
            inv_var,
            persistence,
        }
    }

    /// Dimensions of the space.
    pub fn dims(&self) -> usize {
        self.dims
    }

    /// Writes into `out` the level each emotion component should take to reach `goal` from
    /// the `current` levels. All three have [`SpaceTarget::dims`] values.
    pub fn target_into(&mut self, current: &[f32], goal: &[f32], out: &mut [f32]) {
        let d = self.dims;
        out[..d].copy_from_slice(&goal[..d]);
        if self.persistence.iter().all(|&r| r == 0.0) || self.weights.is_empty() {
            return;
        }
        let mut best = f32::NEG_INFINITY;
        for (w, p) in self.weights.iter_mut().zip(self.points.chunks_exact(d)) {
            let mut ll = 0.0;
            for j in 0..d {
                let diff = current[j] - p[j];
                ll -= 0.5 * diff * diff * self.inv_var[j];
            }
            *w = ll;
            best = best.max(ll);
        }
        let mut total = 0.0;
        for w in &mut self.weights {
            *w = (*w - best).exp();
            total += *w;
        }
        for j in 0..d {
            let source: f32 = self
                .weights
                .iter()
                .zip(self.points.chunks_exact(d))
                .map(|(w, p)| w * p[j])
                .sum::<f32>()
                / total;
            out[j] += self.persistence[j] * (current[j] - source);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_old_model_reads_as_a_one_dimensional_space() {
        let old = EmotionLevels {
            component: Some(2),
            levels: [("happy".to_string(), 1.5), ("sad".to_string(), -0.5)].into(),
            ..EmotionLevels::default()
        };
        assert_eq!(old.space_components(), vec![2]);
        assert_eq!(old.point("happy"), Some(vec![1.5]));
        assert_eq!(old.blend(&[("happy", 1.0), ("sad", 1.0)]), Ok(vec![0.5]));
        assert!(matches!(
            old.blend(&[("angry", 1.0)]),
            Err(BlendError::UnknownEmotion { .. })
        ));
        assert!(matches!(
            old.blend(&[("happy", -1.0)]),
            Err(BlendError::BadWeight { .. })
        ));
    }

    #[test]
    fn points_blend_in_the_space() {
        let point = |level: Vec<f64>| EmotionPoint {
            spread: vec![0.0; level.len()],
            level,
            takes: 1,
        };
        let space = EmotionLevels {
            component: Some(0),
            levels: BTreeMap::new(),
            components: vec![0, 3],
            persistence: vec![],
            points: [
                ("sad".to_string(), point(vec![-1.0, 2.0])),
                ("angry".to_string(), point(vec![1.0, 0.0])),
            ]
            .into(),
        };
        assert_eq!(space.dims(), 2);
        assert_eq!(
            space.blend(&[("sad", 0.5), ("angry", 0.5)]),
            Ok(vec![0.0, 1.0])
        );
    }

    #[test]
    fn a_persistent_component_keeps_the_take_s_own_offset() {
        let point = |level: Vec<f64>| EmotionPoint {
            spread: vec![0.1, 0.1],
            level,
            takes: 4,
        };
        let space = EmotionLevels {
            component: Some(0),
            levels: BTreeMap::new(),
            components: vec![0, 1],
            persistence: vec![0.0, 1.0],
            points: [
                ("happy".to_string(), point(vec![1.0, 0.0])),
                ("sad".to_string(), point(vec![-1.0, 0.5])),
            ]
            .into(),
        };
        let mut t = SpaceTarget::new(&space);
        let mut out = [0.0f32; 2];
        // A happy take whose second component sits 2.0 above happy's level (its sentence).
        t.target_into(&[1.05, 2.0], &[-1.0, 0.5], &mut out);
        assert!((out[0] + 1.0).abs() < 1e-6, "{out:?}");
        assert!((out[1] - 2.5).abs() < 1e-3, "{out:?}");
    }
}
