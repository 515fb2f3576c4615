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

/// Where a take should go in the emotion space to reach a goal point, frame by frame,
/// allocation free (f32, buffers sized at construction); with the maps between components and
/// the space's coordinates ([`SpaceTarget::coordinates_into`], [`SpaceTarget::move_into`]).
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
    /// Components of the model.
    components: usize,
    /// Axes as weights on the components, dims x components.
    axes: Vec<f32>,
    /// Components moved per unit along each axis, dims x components.
    moves: Vec<f32>,
    /// Emotion points, emotions x dims.
    points: Vec<f32>,
    /// 1 / pooled within-emotion variance, per dim.
    inv_var: Vec<f32>,
    persistence: Vec<f32>,
    weights: Vec<f32>,
}

impl SpaceTarget {
    /// The targeting of a model's emotion space, for a model of `components` components.
    pub fn new(levels: &EmotionLevels, components: usize) -> SpaceTarget {
        let dims = levels.dims();
        let (axes, moves) = levels.axis_matrices(components);
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
            components,
            axes: axes.iter().map(|&v| v as f32).collect(),
            moves: moves.iter().map(|&v| v as f32).collect(),
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

    /// Writes the coordinates of components `u` in the space into `out` ([`SpaceTarget::dims`]
    /// values); `u` has the model's components.
    pub fn coordinates_into(&self, u: &[f32], out: &mut [f32]) {
        let m = self.components;
        for (o, axis) in out.iter_mut().zip(self.axes.chunks_exact(m)) {
            *o = axis.iter().zip(u).map(|(a, x)| a * x).sum();
        }
    }

    /// Adds to components `u` the move `scale · delta` in the space (`delta` has
    /// [`SpaceTarget::dims`] values).
    pub fn move_into(&self, delta: &[f32], scale: f32, u: &mut [f32]) {
        let m = self.components;
        for (&d, row) in delta.iter().zip(self.moves.chunks_exact(m)) {
            let step = scale * d;
            if step != 0.0 {
                for (x, w) in u.iter_mut().zip(row) {
                    *x += step * w;
                }
            }
        }
    }

    /// Writes into `out` the coordinates a take should reach for `goal` from its `current`
    /// coordinates. All three have [`SpaceTarget::dims`] values.
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
            axes: vec![],
            moves: vec![],
            conditioning: None,
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
            axes: vec![],
            moves: vec![],
            conditioning: None,
            points: [
                ("happy".to_string(), point(vec![1.0, 0.0])),
                ("sad".to_string(), point(vec![-1.0, 0.5])),
            ]
            .into(),
        };
        let mut t = SpaceTarget::new(&space, 2);
        let mut out = [0.0f32; 2];
        // A happy take whose second component sits 2.0 above happy's level (its sentence).
        t.target_into(&[1.05, 2.0], &[-1.0, 0.5], &mut out);
        assert!((out[0] + 1.0).abs() < 1e-6, "{out:?}");
        assert!((out[1] - 2.5).abs() < 1e-3, "{out:?}");
    }

    #[test]
    fn fitted_axes_read_and_move_components() {
        // One axis along c0 + c1 over three components; moving by 2 along it changes both.
        let s = 0.5f64.sqrt();
        let space = EmotionLevels {
            axes: vec![vec![s, s, 0.0]],
            moves: vec![vec![s, s, 0.0]],
            points: [(
                "happy".to_string(),
                EmotionPoint {
                    level: vec![1.0],
                    spread: vec![0.1],
                    takes: 3,
                },
            )]
            .into(),
            ..EmotionLevels::default()
        };
        assert_eq!(space.dims(), 1);
        let t = SpaceTarget::new(&space, 3);
        let mut at = [0.0f32];
        t.coordinates_into(&[1.0, 1.0, 5.0], &mut at);
        assert!((at[0] - 2.0 * s as f32).abs() < 1e-6);
        let mut u = [0.0f32; 3];
        t.move_into(&[2.0], 0.5, &mut u);
        assert!((u[0] - s as f32).abs() < 1e-6 && (u[1] - s as f32).abs() < 1e-6 && u[2] == 0.0);
        // Without axes, the components are the axes.
        let plain = EmotionLevels {
            components: vec![2],
            ..EmotionLevels::default()
        };
        assert_eq!(
            plain.axis_matrices(3),
            (vec![0.0, 0.0, 1.0], vec![0.0, 0.0, 1.0])
        );
    }
}
