use super::*;
use crate::stabilise::TakeFrames;
use nalgebra::{Rotation3, Vector3};

/// A head band (4 markers), a jaw (4 markers rotating about a hinge with "speech"), and 6
/// free face markers; the head sways when `head` is set. 0.1 mm noise.
fn scene(frames: usize, head: bool) -> (Vec<f32>, Vec<bool>) {
    let band = [
        [0.0, 90.0, -40.0],
        [60.0, 60.0, -60.0],
        [-60.0, 60.0, -60.0],
        [0.0, 120.0, -90.0],
    ];
    let jaw = [
        [0.0, -90.0, 10.0],
        [30.0, -80.0, 0.0],
        [-30.0, -80.0, 0.0],
        [0.0, -70.0, 20.0],
    ];
    let face = [
        [20.0, 20.0, 40.0],
        [-20.0, 20.0, 40.0],
        [25.0, -20.0, 45.0],
        [-25.0, -20.0, 45.0],
        [0.0, -40.0, 60.0],
        [0.0, 40.0, 30.0],
    ];
    let mut xyz = Vec::new();
    let mut state = 7u64;
    let mut noise = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 33) as f64 / (1u64 << 31) as f64 - 0.5) * 0.35
    };
    for f in 0..frames {
        let t = f as f64 / 120.0;
        // Speech and expression are fast next to the head's sway, as on a real face.
        let speech = 0.15 * (0.5 + 0.5 * (17.0 * t).sin() * (5.3 * t).cos());
        let (pose, shift) = if head {
            (
                Rotation3::from_euler_angles(
                    0.05 * (0.4 * t).sin(),
                    0.06 * (0.3 * t).cos(),
                    0.02 * (0.5 * t).sin(),
                ),
                Vector3::new(
                    4.0 * (0.2 * t).sin(),
                    3.0 * (0.35 * t).cos(),
                    2.0 * (0.25 * t).sin(),
                ),
            )
        } else {
            (Rotation3::identity(), Vector3::zeros())
        };
        let hinge = Rotation3::from_euler_angles(speech, 0.0, 0.0);
        let expr = (11.0 * t).sin() * (3.7 * t).sin();
        let points = band
            .iter()
            .map(|p| Vector3::from(*p))
            .chain(jaw.iter().map(|p| {
                hinge * (Vector3::from(*p) - Vector3::new(0.0, -10.0, -80.0))
                    + Vector3::new(0.0, -10.0, -80.0)
            }))
            .chain(face.iter().enumerate().map(|(k, p)| {
                Vector3::from(*p) + Vector3::new(0.0, 4.0 * expr * (k as f64 - 2.5), 3.0 * expr)
            }));
        for p in points {
            let w = pose * p + shift;
            xyz.extend([
                (w.x + noise()) as f32,
                (w.y + noise()) as f32,
                (w.z + noise()) as f32,
            ]);
        }
    }
    let missing = vec![false; frames * 14];
    (xyz, missing)
}

fn decide(head: bool) -> Choice {
    let (xyz, missing) = scene(3000, head);
    let takes = [TakeFrames {
        xyz: &xyz,
        missing: &missing,
    }];
    let frames = MarkerFrames {
        takes: &takes,
        markers: 14,
    };
    let found = search_reference(&frames, &SearchParams::default());
    choose(&found.candidates)
}

#[test]
fn a_moving_head_is_stabilised_on_its_band_not_on_the_jaw() {
    match decide(true) {
        Choice::Stabilise(g) => {
            assert_eq!(g.markers, vec![0, 1, 2, 3], "{g:?}");
            assert!(g.rigid && g.motion_mm > 3.0, "{g:?}");
        }
        other => panic!("expected stabilisation, got {other:?}"),
    }
}

#[test]
fn a_still_head_is_not_stabilised() {
    assert!(
        matches!(decide(false), Choice::StillHead(_)),
        "{:?}",
        decide(false)
    );
}
