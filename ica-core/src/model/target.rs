//! [`SpaceTarget`]: where a take goes in a model's emotion space, and the maps between the
//! components and the space's coordinates, frame by frame and allocation free.

use super::EmotionLevels;

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
