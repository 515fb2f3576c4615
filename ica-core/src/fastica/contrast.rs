//! Contrast functions: the non-linearity `g = G'` of the FastICA update, its derivative, and the
//! negentropy approximation `(E G(y) - E G(nu))^2` used to rank restarts.

/// The non-quadratic function `G` whose expectation FastICA extremises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Contrast {
    /// `G(y) = log cosh y`, `g = tanh y` (alpha = 1): robust, the general-purpose default.
    #[default]
    LogCosh,
    /// `G(y) = -exp(-y^2/2)`, `g = y exp(-y^2/2)`: robust to outliers, for super-Gaussian sources.
    Exp,
    /// `G(y) = y^4/4`, `g = y^3`: kurtosis; fast but sensitive to outliers.
    Cube,
}

impl Contrast {
    /// Name as written in the training report: `logcosh`, `exp` or `cube`.
    pub fn name(self) -> &'static str {
        match self {
            Contrast::LogCosh => "logcosh",
            Contrast::Exp => "exp",
            Contrast::Cube => "cube",
        }
    }

    /// Replaces each `y` by `g(y)` and returns the sum of `g'(y)`.
    pub(crate) fn apply(self, ys: &mut [f64]) -> f64 {
        match self {
            Contrast::LogCosh => map_sum(ys, logcosh_pair),
            Contrast::Exp => map_sum(ys, exp_pair),
            Contrast::Cube => map_sum(ys, cube_pair),
        }
    }

    /// `(g(y), g'(y))` of one value, as [`Contrast::apply`] computes them.
    #[inline(always)]
    pub(crate) fn pair(self, y: f64) -> (f64, f64) {
        match self {
            Contrast::LogCosh => logcosh_pair(y),
            Contrast::Exp => exp_pair(y),
            Contrast::Cube => cube_pair(y),
        }
    }

    /// `G(y)` itself (off the hot path: only for the negentropy score).
    pub(crate) fn big_g(self, y: f64) -> f64 {
        match self {
            // log cosh y = |y| + log(1 + e^{-2|y|}) - log 2, stable for large |y|.
            Contrast::LogCosh => {
                let a = y.abs();
                a + (-2.0 * a).exp().ln_1p() - std::f64::consts::LN_2
            }
            Contrast::Exp => -(-0.5 * y * y).exp(),
            Contrast::Cube => 0.25 * y * y * y * y,
        }
    }

    /// `E G(nu)` for a standard Gaussian `nu`: closed form for `exp` (`-1/sqrt 2`) and `cube`
    /// (`3/4`), Simpson's rule on [-12, 12] for `logcosh` (the tail beyond carries < 1e-30).
    pub(crate) fn gaussian_expectation(self) -> f64 {
        match self {
            Contrast::Exp => -std::f64::consts::FRAC_1_SQRT_2,
            Contrast::Cube => 0.75,
            Contrast::LogCosh => {
                const HALF_WIDTH: f64 = 12.0;
                const STEPS: usize = 4800; // even, as Simpson's rule needs
                let h = 2.0 * HALF_WIDTH / STEPS as f64;
                let f = |y: f64| self.big_g(y) * (-0.5 * y * y).exp();
                let mut sum = f(-HALF_WIDTH) + f(HALF_WIDTH);
                for k in 1..STEPS {
                    let y = -HALF_WIDTH + k as f64 * h;
                    sum += if k % 2 == 1 { 4.0 } else { 2.0 } * f(y);
                }
                sum * h / 3.0 / (2.0 * std::f64::consts::PI).sqrt()
            }
        }
    }

    /// Negentropy approximation of one unit-variance component: `(mean G(y) - E G(nu))^2`.
    pub(crate) fn negentropy(self, ys: &[f64], gaussian: f64) -> f64 {
        if ys.is_empty() {
            return 0.0;
        }
        let mean = ys.iter().map(|&y| self.big_g(y)).sum::<f64>() / ys.len() as f64;
        (mean - gaussian).powi(2)
    }
}

/// Independent accumulators in [`map_sum`]: a single running sum is a sequential dependency
/// that keeps the compiler from vectorising the loop (float addition does not reassociate).
const LANES: usize = 8;

/// Replaces each `y` by `f(y).0` and returns the sum of `f(y).1`, summed in [`LANES`] lanes
/// (a fixed order, so the result is deterministic).
#[inline(always)]
fn map_sum(ys: &mut [f64], f: impl Fn(f64) -> (f64, f64)) -> f64 {
    let mut acc = [0.0f64; LANES];
    let mut chunks = ys.chunks_exact_mut(LANES);
    for chunk in &mut chunks {
        for (y, a) in chunk.iter_mut().zip(acc.iter_mut()) {
            let (g, dg) = f(*y);
            *y = g;
            *a += dg;
        }
    }
    for (y, a) in chunks.into_remainder().iter_mut().zip(acc.iter_mut()) {
        let (g, dg) = f(*y);
        *y = g;
        *a += dg;
    }
    acc.iter().sum()
}

/// `e^x` for `x <= 0` (clamped at -700), branch-free so loops over it vectorise.
///
/// Range reduction `x = k ln2 + r`, `|r| <= ln2/2`, then a degree-11 Taylor polynomial:
/// relative error below 1e-14, which is far below the sampling noise of any average it feeds.
#[inline(always)]
pub(crate) fn exp_fast(x: f64) -> f64 {
    // 1.5 * 2^52: adding it rounds to an integer held in the low mantissa bits.
    const SHIFTER: f64 = 6_755_399_441_055_744.0;
    // ln 2 split so that k * LN2_HI is exact for the k that occur (fdlibm's constants).
    const LN2_HI: f64 = f64::from_bits(0x3FE6_2E42_FEE0_0000);
    const LN2_LO: f64 = f64::from_bits(0x3DEA_39EF_3579_3C76);
    let x = x.max(-700.0);
    let shifted = x * std::f64::consts::LOG2_E + SHIFTER;
    let k = shifted - SHIFTER;
    let r = (x - k * LN2_HI) - k * LN2_LO;
    let mut p = 1.0 / 39_916_800.0;
    p = p * r + 1.0 / 3_628_800.0;
    p = p * r + 1.0 / 362_880.0;
    p = p * r + 1.0 / 40_320.0;
    p = p * r + 1.0 / 5_040.0;
    p = p * r + 1.0 / 720.0;
    p = p * r + 1.0 / 120.0;
    p = p * r + 1.0 / 24.0;
    p = p * r + 1.0 / 6.0;
    p = p * r + 0.5;
    p = p * r + 1.0;
    p = p * r + 1.0;
    // k sits in the low bits of `shifted` as a two's-complement offset from SHIFTER's bits.
    let ki = (shifted.to_bits() as i64).wrapping_sub(SHIFTER.to_bits() as i64);
    let scale = f64::from_bits(((ki + 1023) as u64) << 52);
    p * scale
}

/// `tanh x` in f32 arithmetic: the rational approximation of Eigen's `generic_fast_tanh_float`
/// (odd degree-13 over even degree-6, input clamped where f32 tanh is 1), absolute error below
/// 1e-6.
///
/// The non-linearity only has to be accurate well beyond the fit's tolerance (1e-4) and the
/// sampling noise of the averages it feeds; in f32 it takes a quarter of the f64 exp-based
/// form's time (four lanes, no range reduction), and it dominated the iteration's cost.
/// Sums, products with the data and the convergence test stay f64.
#[inline(always)]
pub(crate) fn tanh_f32(x: f32) -> f32 {
    let x = x.clamp(-TANH_CLAMP, TANH_CLAMP);
    let x2 = x * x;
    let mut p = TANH_P[0];
    for c in &TANH_P[1..] {
        p = p * x2 + c;
    }
    let mut q = TANH_Q[0];
    for c in &TANH_Q[1..] {
        q = q * x2 + c;
    }
    x * p / q
}

/// Where f32 `tanh` is 1: [`tanh_f32`] clamps its input to `±TANH_CLAMP`.
pub(crate) const TANH_CLAMP: f32 = 7.905_311;
/// [`tanh_f32`]'s numerator in `x²`, highest degree first (then times `x`).
pub(crate) const TANH_P: [f32; 7] = [
    -2.760_768_5e-16,
    2.000_188e-13,
    -8.604_672e-11,
    5.122_297e-8,
    1.485_722_4e-5,
    6.372_619_3e-4,
    4.893_524_6e-3,
];
/// [`tanh_f32`]'s denominator in `x²`, highest degree first.
pub(crate) const TANH_Q: [f32; 4] = [1.198_258_4e-6, 1.185_347_1e-4, 2.268_434_6e-3, 4.893_525e-3];

/// `(tanh y, 1 − tanh² y)`, tanh in f32 arithmetic.
#[inline(always)]
fn logcosh_pair(y: f64) -> (f64, f64) {
    let t = f64::from(tanh_f32(y as f32));
    (t, 1.0 - t * t)
}

/// `(y e^{−y²/2}, (1 − y²) e^{−y²/2})`.
#[inline(always)]
fn exp_pair(y: f64) -> (f64, f64) {
    let e = exp_fast(-0.5 * y * y);
    (y * e, (1.0 - y * y) * e)
}

/// `(y³, 3y²)`.
#[inline(always)]
fn cube_pair(y: f64) -> (f64, f64) {
    (y * y * y, 3.0 * y * y)
}

#[cfg(test)]
mod tests;
