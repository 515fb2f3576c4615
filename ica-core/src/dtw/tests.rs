use super::*;

/// Minimum cost over every monotone, continuous path: exponential, for tiny cases only.
fn brute(a: &[f64], b: &[f64], dim: usize, i: usize, j: usize) -> f64 {
    let local = sq_dist(&a[i * dim..(i + 1) * dim], &b[j * dim..(j + 1) * dim]);
    if i == 0 && j == 0 {
        return local;
    }
    let mut best = f64::INFINITY;
    if i > 0 && j > 0 {
        best = best.min(brute(a, b, dim, i - 1, j - 1));
    }
    if i > 0 {
        best = best.min(brute(a, b, dim, i - 1, j));
    }
    if j > 0 {
        best = best.min(brute(a, b, dim, i, j - 1));
    }
    best + local
}

fn lcg(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

fn path_cost(a: &[f64], b: &[f64], dim: usize, path: &[(usize, usize)]) -> f64 {
    path.iter()
        .map(|&(i, j)| sq_dist(&a[i * dim..(i + 1) * dim], &b[j * dim..(j + 1) * dim]))
        .sum()
}

fn assert_valid_path(path: &[(usize, usize)], n: usize, m: usize) {
    assert_eq!(path[0], (0, 0));
    assert_eq!(*path.last().expect("non-empty"), (n - 1, m - 1));
    for w in path.windows(2) {
        let (di, dj) = (w[1].0 - w[0].0, w[1].1 - w[0].1);
        assert!(di <= 1 && dj <= 1 && di + dj >= 1, "bad step {w:?}");
    }
}

#[test]
fn matches_brute_force_on_small_cases() {
    let mut seed = 42;
    for n in 1..=6 {
        for m in 1..=6 {
            for dim in 1..=3 {
                let a: Vec<f64> = (0..n * dim).map(|_| lcg(&mut seed)).collect();
                let b: Vec<f64> = (0..m * dim).map(|_| lcg(&mut seed)).collect();
                let al = align(&a, &b, dim, None).expect("valid input");
                let expected = brute(&a, &b, dim, n - 1, m - 1);
                assert!((al.cost - expected).abs() < 1e-12, "n={n} m={m} dim={dim}");
                assert_valid_path(&al.path, n, m);
                assert!((path_cost(&a, &b, dim, &al.path) - al.cost).abs() < 1e-12);
            }
        }
    }
}

#[test]
fn wide_band_equals_full_search() {
    let mut seed = 7;
    let a: Vec<f64> = (0..40 * 2).map(|_| lcg(&mut seed)).collect();
    let b: Vec<f64> = (0..55 * 2).map(|_| lcg(&mut seed)).collect();
    let full = align(&a, &b, 2, None).expect("valid");
    let banded = align(&a, &b, 2, Some(60)).expect("valid");
    assert_eq!(full, banded);
}

#[test]
fn narrow_band_costs_at_least_full_and_stays_in_band() {
    let mut seed = 9;
    let a: Vec<f64> = (0..50).map(|_| lcg(&mut seed)).collect();
    let b: Vec<f64> = (0..80).map(|_| lcg(&mut seed)).collect();
    let full = align(&a, &b, 1, None).expect("valid");
    let banded = align(&a, &b, 1, Some(3)).expect("valid");
    assert!(banded.cost >= full.cost - 1e-12);
    assert!(banded.cost.is_finite());
    assert_valid_path(&banded.path, 50, 80);
    let band = Band {
        n: 50,
        m: 80,
        radius: Some(3),
    };
    for &(i, j) in &banded.path {
        let (lo, hi) = band.window(i);
        assert!(j >= lo && j <= hi);
    }
}

#[test]
fn recovers_a_known_warp() {
    // b is a time-warped copy of a: b(t) = a(w(t)) with a smooth monotone warp.
    let n = 300;
    let signal = |t: f64| [(t * 0.07).sin(), (t * 0.031).cos()];
    let a: Vec<f64> = (0..n).flat_map(|t| signal(t as f64)).collect();
    let m = 360;
    let warp = |j: f64| {
        let u = j / (m - 1) as f64;
        (u + 0.08 * (std::f64::consts::PI * u).sin()).min(1.0) * (n - 1) as f64
    };
    let b: Vec<f64> = (0..m).flat_map(|j| signal(warp(j as f64))).collect();
    let al = align(&a, &b, 2, Some(40)).expect("valid");
    let mut worst: f64 = 0.0;
    for &(i, j) in &al.path {
        worst = worst.max((warp(j as f64) - i as f64).abs());
    }
    assert!(worst <= 2.0, "alignment error {worst} frames");
}

#[test]
fn rejects_bad_input() {
    assert_eq!(align(&[], &[1.0], 1, None), Err(DtwError::Empty));
    assert!(matches!(
        align(&[1.0, 2.0, 3.0], &[1.0, 2.0], 2, None),
        Err(DtwError::BadShape { .. })
    ));
    assert_eq!(
        align(&[1.0, f64::NAN], &[1.0], 1, None),
        Err(DtwError::NonFinite { index: 1 })
    );
}

#[test]
fn warp_map_averages_matches() {
    let path = [(0, 0), (0, 1), (1, 2), (2, 3), (2, 4)];
    assert_eq!(warp_map(&path, 3), vec![0.5, 2.0, 3.5]);
}
