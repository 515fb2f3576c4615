use nalgebra::DMatrix;

use super::Fused;
use crate::fastica::Contrast;

/// A deterministic pseudo-random `frames x m` block in [-3, 3).
fn frames(frames: usize, m: usize, seed: u64) -> Vec<f64> {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    (0..frames * m)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 6.0 - 3.0
        })
        .collect()
}

/// The sums from their definition, one frame at a time.
fn reference(w: &DMatrix<f64>, z: &[f64], contrast: Contrast) -> (DMatrix<f64>, Vec<f64>) {
    let (k, m) = w.shape();
    let (mut b, mut gp) = (DMatrix::zeros(m, k), vec![0.0; k]);
    for zt in z.chunks_exact(m) {
        for i in 0..k {
            let y: f64 = (0..m).map(|j| w[(i, j)] * zt[j]).sum();
            let (g, dg) = contrast.pair(y);
            gp[i] += dg;
            for j in 0..m {
                b[(j, i)] += zt[j] * g;
            }
        }
    }
    (b, gp)
}

fn assert_close(got: &(DMatrix<f64>, Vec<f64>), want: &(DMatrix<f64>, Vec<f64>), what: &str) {
    let scale = want.0.amax().max(1.0);
    let db = (&got.0 - &want.0).amax() / scale;
    let dg = got
        .1
        .iter()
        .zip(&want.1)
        .map(|(a, b)| (a - b).abs() / b.abs().max(1.0))
        .fold(0.0, f64::max);
    assert!(
        db < 1e-12 && dg < 1e-12,
        "{what}: B off by {db:e}, g' by {dg:e}"
    );
}

#[test]
fn fused_sums_match_their_definition_with_and_without_simd() {
    // Shapes: the common one, padded lanes (k = 7), one row (deflation), more rows than a
    // tile holds (k = 30), an odd row count of B (m = 5); frame counts across tile borders.
    for (k, m, n) in [
        (20, 20, 300),
        (7, 5, 129),
        (1, 6, 128),
        (30, 30, 257),
        (3, 3, 1),
    ] {
        let w = DMatrix::from_vec(k, m, frames(k, m, 7 + k as u64));
        let z = frames(n, m, n as u64);
        for contrast in [Contrast::LogCosh, Contrast::Exp, Contrast::Cube] {
            let want = reference(&w, &z, contrast);
            let mut simd = Fused::new(&w);
            // Two calls and a merge, as the accumulator's halves are.
            let (left, right) = z.split_at(n / 2 * m);
            simd.add(left, contrast);
            let mut other = Fused::new(&w);
            other.add(right, contrast);
            simd.merge(&other);
            let mut scalar = Fused::new(&w);
            scalar.v3 = None;
            scalar.add(&z, contrast);
            let what = format!("k {k}, m {m}, {n} frames, {}", contrast.name());
            assert_close(
                &simd.sums(),
                &want,
                &format!("{what}, simd {}", simd.v3.is_some()),
            );
            assert_close(&scalar.sums(), &want, &format!("{what}, scalar"));
        }
    }
}

#[test]
fn simd_tanh_is_the_scalar_one_bit_for_bit() {
    let Some(v3) = pulp::x86::V3::try_new() else {
        eprintln!("no AVX2 + FMA here: the scalar path is the only one");
        return;
    };
    let xs = frames(4096, 1, 3);
    for x in xs
        .chunks_exact(4)
        .chain([[0.0, -0.0, 40.0, -40.0].as_slice()])
    {
        let x32: [f32; 4] = std::array::from_fn(|i| (x[i] * 3.0) as f32);
        let got: [f32; 4] = pulp::cast(super::tanh_f32x4(v3, pulp::cast(x32)));
        let want = x32.map(crate::fastica::contrast::tanh_f32);
        assert_eq!(got.map(f32::to_bits), want.map(f32::to_bits), "at {x32:?}");
    }
}
