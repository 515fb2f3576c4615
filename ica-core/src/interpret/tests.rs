use nalgebra::DMatrix;

use super::*;

/// Direct evaluation of Eq. 3–4 by reconstructing the region's markers.
fn region_brute(mixing: &DMatrix<f64>, series: &[f64], region: &[usize], e: &[usize]) -> Vec<f64> {
    let m = mixing.ncols();
    let frames = series.len() / m;
    let d = |subset: &dyn Fn(usize) -> bool| {
        let mut acc = 0.0;
        for t in 0..frames {
            for &r in region {
                for row in r * 3..r * 3 + 3 {
                    let diff: f64 = (0..m)
                        .filter(|&k| !subset(k))
                        .map(|k| mixing[(row, k)] * series[t * m + k])
                        .sum();
                    acc += diff * diff;
                }
            }
        }
        (acc / (frames * region.len()) as f64).sqrt()
    };
    let d_e = d(&|k| e.contains(&k));
    (0..m)
        .map(|i| {
            if e.contains(&i) {
                0.0
            } else {
                d(&|k| e.contains(&k) || k == i) - d_e
            }
        })
        .collect()
}

#[test]
fn region_metric_matches_direct_reconstruction() {
    let m = 4;
    let mixing = DMatrix::from_fn(5 * 3, m, |r, c| ((r * 7 + c * 3) % 11) as f64 - 5.0);
    let series: Vec<f64> = (0..50 * m)
        .map(|i| ((i * 13 % 17) as f64 - 8.0) / 3.0)
        .collect();
    for e in [vec![], vec![2]] {
        let fast = region_distance(&mixing, &[&series], &[1, 3], &e).expect("valid");
        let slow = region_brute(&mixing, &series, &[1, 3], &e);
        for (f, s) in fast.iter().zip(&slow) {
            assert!((f - s).abs() < 1e-9, "{f} vs {s}");
        }
    }
}

#[test]
fn emotion_distance_peaks_on_the_offset_component() {
    // Component 1 carries a constant offset between the takes; the others are the same
    // motion at a different speed.
    let m = 3;
    let make = |n: usize, level: f64| -> Vec<f64> {
        (0..n)
            .flat_map(|t| {
                let s = t as f64 / n as f64 * 12.0;
                [s.sin(), level + 0.1 * (2.0 * s).cos(), (0.5 * s).cos()]
            })
            .collect()
    };
    let a = make(200, 1.0);
    let b = make(240, -1.0);
    let d = emotion_distance(&[(&a, &b)], m, Some(40)).expect("valid");
    assert!(d.per_component[1] > 1.9, "{:?}", d.per_component);
    assert!(
        d.per_component[0] < 0.2 && d.per_component[2] < 0.2,
        "{:?}",
        d.per_component
    );
    assert_eq!(
        emotion_components(&d.per_component, &LabelRules::default()),
        vec![1]
    );
}

#[test]
fn labels_follow_the_largest_relative_region_influence() {
    let mouth = [-3.0, -0.1, -2.5, -0.05, 0.0];
    let brows = [-0.2, -1.5, -0.1, -0.1, 0.0];
    let lids = [-0.1, -0.3, -0.1, -0.9, 0.0];
    let regions = [
        (Role::Speech, &mouth[..]),
        (Role::Eyebrows, &brows[..]),
        (Role::Eyelids, &lids[..]),
    ];
    let roles = label(5, &[4], &regions, &LabelRules::default());
    assert_eq!(
        roles,
        vec![
            Role::Speech,
            Role::Eyebrows,
            Role::Speech,
            Role::Eyelids,
            Role::Emotion
        ]
    );
}

#[test]
fn no_clear_peak_means_no_emotion_component() {
    assert!(emotion_components(&[1.0, 1.1, 0.9, 1.2], &LabelRules::default()).is_empty());
}

#[test]
fn accumulators_fed_one_input_at_a_time_match_the_whole_slice_metrics() {
    let m = 3;
    let take = |n: usize, phase: f64| -> Vec<f64> {
        (0..n * m)
            .map(|i| ((i as f64) * 0.37 + phase).sin() + (i % m) as f64 * 0.5)
            .collect()
    };
    let (a, b, c) = (take(40, 0.0), take(48, 1.0), take(36, 2.0));
    let pairs: [(&[f64], &[f64]); 2] = [(&a, &b), (&b, &c)];
    let whole = emotion_distance(&pairs, m, Some(12)).expect("valid");
    let mut acc = EmotionDistanceAcc::new(m, Some(12));
    for (x, y) in pairs {
        acc.add_pair(x, y).expect("valid");
    }
    assert_eq!(acc.finish(), whole);
    let mut level = LevelDistanceAcc::new(m);
    let means: Vec<Vec<f64>> = [&a, &b, &c]
        .iter()
        .map(|s| series_means(s, m).expect("valid"))
        .collect();
    level.add_means(&means[0], &means[1]).expect("valid");
    level.add_means(&means[1], &means[2]).expect("valid");
    assert_eq!(level.finish(), level_distance(&pairs, m).expect("valid"));
    // Moments of the takes one by one give the direct metric over all of them, for any
    // emotion set chosen afterwards.
    let mixing = DMatrix::from_fn(4 * 3, m, |r, c| ((r * 5 + c * 7) % 9) as f64 - 4.0);
    let mut moments = ComponentMoments::new(m);
    for s in [&a, &b, &c] {
        moments.add_series(s).expect("valid");
    }
    let all: Vec<f64> = [a, b, c].concat();
    for e in [vec![], vec![1], vec![0, 2]] {
        let got = moments
            .region_distance(&mixing, &[0, 2], &e)
            .expect("valid");
        let want = region_brute(&mixing, &all, &[0, 2], &e);
        for (g, w) in got.iter().zip(&want) {
            assert!((g - w).abs() < 1e-9, "{g} vs {w}");
        }
    }
    assert!(matches!(
        moments.region_distance(&DMatrix::zeros(12, 2), &[0], &[]),
        Err(InterpretError::ComponentCountMismatch { .. })
    ));
}
