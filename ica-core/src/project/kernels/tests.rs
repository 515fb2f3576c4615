use super::*;

/// Runs the checks with plain and, where the CPU has it, fused multiply-adds.
struct Checks;

impl Kernel for Checks {
    type Output = ();
    fn run<A: MulAdd>(self) {
        let n = 37;
        let a: Vec<f32> = (0..n).map(|i| (i as f32 * 0.37).sin()).collect();
        let b: Vec<f32> = (0..n).map(|i| (i as f32 * 0.11).cos()).collect();
        let naive: f32 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
        assert!((dot::<A>(&a, &b) - naive).abs() < 1e-5);
        // Wᵀ with 2 components padded to 8: u = [a·b, b·b].
        let wt: Vec<f32> = (0..n)
            .flat_map(|j| [a[j], b[j], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
            .collect();
        let zeros = vec![0.0_f32; n];
        let mut u = [0.0_f32; 2];
        panel_gemv::<8, A>(&wt, &b, &zeros, &mut u);
        assert!((u[0] - naive).abs() < 1e-5);
        assert!((u[1] - dot::<A>(&b, &b)).abs() < 1e-5);
        let mut y = b.clone();
        axpy4::<A>(
            [1.0, 2.0, 0.0, -1.0],
            [&a[..], &a[..], &b[..], &b[..]],
            &mut y,
        );
        for j in 0..n {
            assert!((y[j] - (b[j] + 3.0 * a[j] - b[j])).abs() < 1e-5);
        }
        let mut z = vec![f32::NAN; n];
        axpy4_onto::<A>(
            &b,
            [1.0, 2.0, 0.0, -1.0],
            [&a[..], &a[..], &b[..], &b[..]],
            &mut z,
        );
        assert_eq!(z, y);
        // One non-finite coordinate poisons every component (what project_masked_into's
        // fast path relies on), even where W is zero (the padded lanes here).
        let mut x = b.clone();
        x[36] = f32::INFINITY;
        let mut u8 = [0.0_f32; 8];
        panel_gemv::<8, A>(&wt, &x, &zeros, &mut u8);
        assert!(u8.iter().all(|v| !v.is_finite()));
    }
}

#[test]
fn kernels_match_naive_loops() {
    Checks.run::<Plain>();
    Simd::detect().run(Checks);
}
