use super::*;
use nalgebra::Rotation3;

/// 6 markers: 4 rigid (a tetrahedron) and 2 that move on their own.
fn scene(frames: usize) -> (Vec<f32>, Vec<Pose>) {
    let rigid = [
        [0.0, 80.0, 20.0],
        [40.0, 60.0, 10.0],
        [-40.0, 60.0, 10.0],
        [0.0, 30.0, 60.0],
    ];
    let mut out = Vec::new();
    let mut poses = Vec::new();
    for f in 0..frames {
        let t = f as f64 * 0.05;
        let rot =
            Rotation3::from_euler_angles(0.1 * t.sin(), 0.2 * (0.7 * t).sin(), 0.05 * t.cos());
        let pose = Pose {
            rotation: *rot.matrix(),
            translation: Vector3::new(5.0 * t.sin(), 3.0 * t.cos(), 100.0),
        };
        let free = [
            [20.0 + 8.0 * (3.0 * t).sin(), -30.0, 40.0],
            [-20.0, -30.0 - 6.0 * t.cos(), 40.0],
        ];
        for p in rigid.iter().chain(free.iter()) {
            let w = pose.rotation * Vector3::from(*p) + pose.translation;
            out.extend([w.x as f32, w.y as f32, w.z as f32]);
        }
        poses.push(pose);
    }
    (out, poses)
}

#[test]
fn round_trip_removes_and_restores_head_motion() {
    let (frames, _) = scene(100);
    let mut missing = vec![false; 100 * 6];
    missing[10 * 6 + 2] = true; // a reference marker drops out in frame 10
    let mut st = Stabiliser::fit(&frames, &missing, 6, vec![0, 1, 2, 3]).expect("fit");
    let mut head = vec![0.0f32; 18];
    let mut back = vec![0.0f32; 18];
    let mut first_head: Option<Vec<f32>> = None;
    for f in 0..100 {
        let fr = &frames[f * 18..(f + 1) * 18];
        let miss = &missing[f * 6..(f + 1) * 6];
        let est = st.estimate(fr, miss);
        assert!(!est.held);
        assert!(est.residual_mm < 1e-3, "residual {}", est.residual_mm);
        to_head_into(&est.pose, fr, miss, &mut head);
        to_world_into(&est.pose, &head, &mut back);
        for m in (0..6).filter(|&m| !miss[m]) {
            for a in 0..3 {
                assert!((back[m * 3 + a] - fr[m * 3 + a]).abs() < 1e-3);
            }
        }
        // Rigid markers stay put in head coordinates.
        let first = first_head.get_or_insert_with(|| head.clone());
        for m in [0, 1, 3] {
            for a in 0..3 {
                assert!((head[m * 3 + a] - first[m * 3 + a]).abs() < 1e-3);
            }
        }
    }
}

#[test]
fn too_few_references_hold_the_last_pose() {
    let (frames, _) = scene(3);
    let missing = vec![false; 18];
    let mut st = Stabiliser::fit(&frames, &missing, 6, vec![0, 1, 2, 3]).expect("fit");
    let good = st.estimate(&frames[..18], &missing[..6]);
    let gone = [true, true, false, false, false, false];
    let held = st.estimate(&frames[18..36], &gone);
    assert!(held.held);
    assert_eq!(held.pose, good.pose);
}

#[test]
fn bad_setups_are_errors() {
    let (frames, _) = scene(3);
    let missing = vec![false; 18];
    assert_eq!(
        Stabiliser::fit(&frames, &missing, 6, vec![0, 1]).expect_err("two references"),
        StabiliseError::TooFewReferences(2)
    );
    assert!(matches!(
        Stabiliser::fit(&frames, &missing, 6, vec![0, 1, 9]),
        Err(StabiliseError::BadIndex { index: 9, .. })
    ));
    // Three collinear points.
    let line: Vec<f32> = (0..3).flat_map(|k| [k as f32 * 10.0, 0.0, 0.0]).collect();
    assert_eq!(
        Stabiliser::fit(&line, &[false; 3], 3, vec![0, 1, 2]).expect_err("collinear"),
        StabiliseError::Degenerate
    );
}

/// Issue 35: the vectorised transforms give nalgebra's products to the bit, for marker counts
/// around the groups of four and with missing markers copied.
#[test]
fn transforms_match_nalgebra_products_to_the_bit() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(35);
    for markers in [1, 3, 4, 5, 7, 8, 109] {
        for _ in 0..50 {
            let angles: [f64; 3] = std::array::from_fn(|_| rng.random_range(-3.0..3.0));
            let pose = Pose {
                rotation: *Rotation3::from_euler_angles(angles[0], angles[1], angles[2]).matrix(),
                translation: Vector3::from_fn(|_, _| rng.random_range(-2000.0..2000.0)),
            };
            let world: Vec<f32> = (0..markers * 3)
                .map(|_| rng.random_range(-3000.0..3000.0))
                .collect();
            let missing: Vec<bool> = (0..markers).map(|_| rng.random_bool(0.2)).collect();
            let (mut head, mut back) = (vec![0.0; markers * 3], vec![0.0; markers * 3]);
            to_head_into(&pose, &world, &missing, &mut head);
            to_world_into(&pose, &head, &mut back);
            let inv = pose.rotation.transpose();
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            for m in 0..markers {
                let p = point(&world, m);
                let h = inv * (p - pose.translation);
                let want: [f32; 3] = match missing[m] {
                    true => [p.x as f32, p.y as f32, p.z as f32],
                    false => [h.x as f32, h.y as f32, h.z as f32],
                };
                let got = bits(&head[m * 3..m * 3 + 3]);
                assert_eq!(got, bits(&want), "head, marker {m} of {markers}");
                let w = pose.rotation * point(&head, m) + pose.translation;
                let want = [w.x as f32, w.y as f32, w.z as f32];
                let got = bits(&back[m * 3..m * 3 + 3]);
                assert_eq!(got, bits(&want), "world, marker {m} of {markers}");
            }
        }
    }
}
