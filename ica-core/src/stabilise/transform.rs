//! A frame between world and head coordinates, given its pose: every frame of `edit`,
//! `project` and `serve` goes through [`to_head_into`], and every edited one back through
//! [`to_world_into`].
//!
//! Both sum in the order nalgebra's `r.transpose() * (p - t)` and `r * p + t` sum (column by
//! column), without fused multiply-adds, so their output is those products' to the bit. Four
//! markers at a time, each coordinate of the four in a row, inside pulp's AVX2 dispatch where
//! the CPU has it: the compiler vectorises across the markers (they were a fifth of `edit`'s
//! time as one nalgebra product per marker, issue 35).

use super::Pose;

/// Maps a frame from world to head coordinates: `head = Rᵀ (world − t)`. Missing samples are
/// copied unchanged.
pub fn to_head_into(pose: &Pose, world: &[f32], missing: &[bool], head: &mut [f32]) {
    let op = ToHead {
        transform: Transform::inverse_of(pose),
        world,
        missing,
        head,
    };
    #[cfg(target_arch = "x86_64")]
    if let Some(v3) = pulp::x86::V3::try_new() {
        return pulp::Simd::vectorize(v3, op);
    }
    op.run();
}

/// Maps a frame from head to world coordinates: `world = R · head + t`.
pub fn to_world_into(pose: &Pose, head: &[f32], world: &mut [f32]) {
    let op = ToWorld {
        transform: Transform::of(pose),
        head,
        world,
    };
    #[cfg(target_arch = "x86_64")]
    if let Some(v3) = pulp::x86::V3::try_new() {
        return pulp::Simd::vectorize(v3, op);
    }
    op.run();
}

/// `y = A (p − before) + after` for a 3 x 3 `A` given by its columns.
struct Transform {
    columns: [[f64; 3]; 3],
    before: [f64; 3],
    after: [f64; 3],
}

impl Transform {
    /// World to head: `Rᵀ (p − t)`; column j of `Rᵀ` is row j of `R`.
    fn inverse_of(pose: &Pose) -> Transform {
        let (r, t) = (&pose.rotation, &pose.translation);
        let row = |j: usize| [r[(j, 0)], r[(j, 1)], r[(j, 2)]];
        Transform {
            columns: [row(0), row(1), row(2)],
            before: [t.x, t.y, t.z],
            after: [0.0; 3],
        }
    }

    /// Head to world: `R p + t`.
    fn of(pose: &Pose) -> Transform {
        let (r, t) = (&pose.rotation, &pose.translation);
        let column = |j: usize| [r[(0, j)], r[(1, j)], r[(2, j)]];
        Transform {
            columns: [column(0), column(1), column(2)],
            before: [0.0; 3],
            after: [t.x, t.y, t.z],
        }
    }

    /// Maps `L` markers (`from`, `to`: 3 L values); a marker whose `keep` is set is copied.
    /// `after` is added only when `add` (nalgebra's `Rᵀ (p − t)` adds nothing, and `+ 0.0`
    /// would turn a `-0.0` into `0.0`); subtracting a zero `before` changes no value.
    #[inline(always)]
    fn map<const L: usize>(&self, from: &[f32], keep: [bool; L], to: &mut [f32], add: bool) {
        let mut d = [[0.0f64; L]; 3];
        for k in 0..L {
            for a in 0..3 {
                d[a][k] = f64::from(from[3 * k + a]) - self.before[a];
            }
        }
        let [c0, c1, c2] = &self.columns;
        for i in 0..3 {
            for k in 0..L {
                let mut y = c0[i] * d[0][k] + c1[i] * d[1][k] + c2[i] * d[2][k];
                if add {
                    y += self.after[i];
                }
                to[3 * k + i] = if keep[k] { from[3 * k + i] } else { y as f32 };
            }
        }
    }
}

/// [`to_head_into`] as a pulp operation.
struct ToHead<'a> {
    transform: Transform,
    world: &'a [f32],
    missing: &'a [bool],
    head: &'a mut [f32],
}

impl ToHead<'_> {
    #[inline(always)]
    fn run(self) {
        let n = self
            .missing
            .len()
            .min(self.world.len() / 3)
            .min(self.head.len() / 3);
        let (world, head) = (&self.world[..n * 3], &mut self.head[..n * 3]);
        let missing = &self.missing[..n];
        let quads = world
            .chunks_exact(12)
            .zip(head.chunks_exact_mut(12))
            .zip(missing.chunks_exact(4));
        for ((w, h), gone) in quads {
            let keep = [gone[0], gone[1], gone[2], gone[3]];
            self.transform.map::<4>(w, keep, h, false);
        }
        let whole = n / 4 * 4;
        let tail = world[whole * 3..]
            .chunks_exact(3)
            .zip(head[whole * 3..].chunks_exact_mut(3))
            .zip(&missing[whole..]);
        for ((w, h), &gone) in tail {
            self.transform.map::<1>(w, [gone], h, false);
        }
    }
}

impl pulp::WithSimd for ToHead<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        self.run();
    }
}

/// [`to_world_into`] as a pulp operation.
struct ToWorld<'a> {
    transform: Transform,
    head: &'a [f32],
    world: &'a mut [f32],
}

impl ToWorld<'_> {
    #[inline(always)]
    fn run(self) {
        let n = self.head.len().min(self.world.len()) / 3;
        let (head, world) = (&self.head[..n * 3], &mut self.world[..n * 3]);
        for (h, w) in head.chunks_exact(12).zip(world.chunks_exact_mut(12)) {
            self.transform.map::<4>(h, [false; 4], w, true);
        }
        let whole = n / 4 * 4;
        let tail = head[whole * 3..].chunks_exact(3);
        for (h, w) in tail.zip(world[whole * 3..].chunks_exact_mut(3)) {
            self.transform.map::<1>(h, [false], w, true);
        }
    }
}

impl pulp::WithSimd for ToWorld<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        self.run();
    }
}
