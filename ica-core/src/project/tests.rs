use super::*;
use crate::TrainReport;
use nalgebra::DMatrix;

/// A random model of `markers` markers and `m` components (seeded, no rand dependency).
fn model(markers: usize, m: usize, seed: u64) -> IcaModel {
    let mut state = seed;
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let n = 3 * markers;
    let mixing = DMatrix::from_fn(n, m, |_, _| 4.0 * next());
    let mean = (0..n).map(|_| 1000.0 + 200.0 * next()).collect();
    let labels = (0..markers).map(|i| format!("m{i}")).collect();
    IcaModel::new(labels, 120.0, mean, mixing, TrainReport::untrained(n, m))
        .expect("random mixing has full rank")
}

fn frames(model: &IcaModel, count: usize) -> Vec<Vec<f32>> {
    (0..count)
        .map(|f| {
            model
                .mean()
                .iter()
                .enumerate()
                .map(|(j, &v)| (v + 5.0 * ((f * 31 + j * 7) as f64 * 0.37).sin()) as f32)
                .collect()
        })
        .collect()
}

#[test]
fn the_simd_layout_agrees_with_the_portable_kernels() {
    for (markers, m) in [(40, 1), (41, 6), (109, 10), (109, 20), (100, 32), (37, 33)] {
        let model = model(markers, m, m as u64);
        let mut fast = Projector::new(&model);
        let mut portable = fast.clone();
        #[cfg(target_arch = "x86_64")]
        {
            portable.avx2 = None;
        }
        let mask: Vec<bool> = (0..markers).map(|i| i % 5 == 2).collect();
        for (f, x) in frames(&model, 6).iter().enumerate() {
            let missing = (f % 2 == 1).then_some(&mask[..]);
            let mut edit = FrameEdit::identity(m);
            edit.set_offset(m / 2, 0.7).expect("in range");
            let (mut ua, mut xa) = (vec![0.0; m], vec![0.0; 3 * markers]);
            let (mut ub, mut xb) = (ua.clone(), xa.clone());
            let sa = fast
                .process_into(x, missing, &edit, &mut xa, &mut ua)
                .expect("sizes");
            let sb = portable
                .process_into(x, missing, &edit, &mut xb, &mut ub)
                .expect("sizes");
            assert_eq!(sa.masked, sb.masked);
            for (a, b) in ua.iter().zip(&ub) {
                assert!(
                    (a - b).abs() < 1e-3,
                    "{markers} markers, m = {m}: u {a} {b}"
                );
            }
            for (a, b) in xa.iter().zip(&xb) {
                assert!(
                    (a - b).abs() < 1e-3,
                    "{markers} markers, m = {m}: x {a} {b}"
                );
            }
        }
    }
}

#[test]
fn a_factorisation_kept_for_an_occlusion_gives_what_a_fresh_one_gives() {
    let (markers, m) = (60, 12);
    let model = model(markers, m, 5);
    let mut kept = Projector::new(&model);
    let masks: Vec<Vec<bool>> = (0..3)
        .map(|k| (0..markers).map(|i| (i + k) % 4 == 0).collect())
        .collect();
    // Masks in the order A A B A C C: kept factorisations for the repeats.
    let order = [0, 0, 1, 0, 2, 2];
    for (x, &k) in frames(&model, order.len()).iter().zip(&order) {
        let mut fresh = Projector::new(&model);
        // The same prior (last good components) as the kept projector's.
        fresh.last_u.copy_from_slice(&kept.last_u);
        let (mut ua, mut ub) = (vec![0.0; m], vec![0.0; m]);
        let sa = kept
            .project_masked_into(x, Some(&masks[k]), &mut ua)
            .expect("sizes");
        let sb = fresh
            .project_masked_into(x, Some(&masks[k]), &mut ub)
            .expect("sizes");
        assert_eq!(sa, sb);
        assert_eq!(ua, ub);
    }
}
