use nalgebra::DMatrix;

use super::*;

/// Take means of a session: 8 sentences x 4 emotions on 2 emotion directions, spread over 5
/// components by `mix` (5 x 5); each sentence adds its own content to the last three
/// directions and a little to the emotion plane; each take a small wobble.
fn session(mix: &DMatrix<f64>) -> Vec<(String, String, Vec<f64>, Vec<f64>)> {
    let points = [[0.0, 0.0], [1.0, 0.0], [-0.6, -0.8], [-0.2, 1.0]];
    let names = ["neutral", "happy", "sad", "angry"];
    let mut out = Vec::new();
    for s in 0..8 {
        let content: Vec<f64> = (0..5)
            .map(|k| ((s * 7 + k * 3) % 11) as f64 * 0.2 - 1.0)
            .collect();
        let mut first: Option<Vec<f64>> = None;
        for (e, p) in points.iter().enumerate() {
            let wobble = |k: usize| (((s * 5 + e * 3 + k) * 37) % 17) as f64 * 0.004 - 0.032;
            let raw: Vec<f64> = (0..5)
                .map(|k| {
                    let emotion = if k < 2 { p[k] } else { 0.0 };
                    let c = if k < 2 { 0.1 * content[k] } else { content[k] };
                    emotion + c + wobble(k)
                })
                .collect();
            let means: Vec<f64> = (mix * DVector::from_vec(raw)).iter().copied().collect();
            // The aligned offset: this take's level less the first take's, the content gone.
            let aligned = match &first {
                None => vec![0.0; 5],
                Some(f) => means.iter().zip(f).map(|(a, b)| a - b).collect(),
            };
            first.get_or_insert(means.clone());
            out.push((format!("s{s}"), names[e].to_string(), means, aligned));
        }
    }
    out
}

fn basis(rows: &[(String, String, Vec<f64>, Vec<f64>)], aligned: bool) -> EmotionBasis {
    let takes: Vec<BasisTake<'_>> = rows
        .iter()
        .map(|(s, e, means, off)| BasisTake {
            sentence: s,
            emotion: e,
            means,
            aligned: aligned.then_some(off.as_slice()),
        })
        .collect();
    emotion_basis(&takes, 5).expect("a paired session")
}

/// The move in components from emotion `a`'s point to `b`'s.
fn move_between(b: &EmotionBasis, from: &str, to: &str) -> DVector<f64> {
    let (p, q) = (&b.points[from].level, &b.points[to].level);
    let mut out = DVector::zeros(5);
    for (j, row) in b.moves.iter().enumerate() {
        out += DVector::from_vec(row.clone()) * (q[j] - p[j]);
    }
    out
}

#[test]
fn two_directions_spread_over_components_give_a_two_dimensional_space() {
    // A rotation that splits each emotion direction over every component.
    let rot = DMatrix::from_fn(5, 5, |i, j| ((i * 3 + j * 5) % 7) as f64 - 3.0)
        .qr()
        .q();
    for aligned in [true, false] {
        let b = basis(&session(&rot), aligned);
        assert_eq!(b.dims(), 2, "{:?}", b.tests);
        let product = DMatrix::from_fn(2, 2, |i, j| {
            b.project[i]
                .iter()
                .zip(&b.moves[j])
                .map(|(x, y)| x * y)
                .sum::<f64>()
        });
        assert!((product - DMatrix::identity(2, 2)).norm() < 1e-9);
        // neutral -> happy moves (1, 0) in the emotion plane, whatever the split.
        let want = &rot * DVector::from_vec(vec![1.0, 0.0, 0.0, 0.0, 0.0]);
        let got = move_between(&b, "neutral", "happy");
        assert!(
            (&got - &want).norm() < 0.05,
            "aligned {aligned}: {got} vs {want}"
        );
        assert_eq!(b.points["sad"].takes, 8);
    }
}

#[test]
fn the_space_turns_with_the_components() {
    let rot = DMatrix::from_fn(5, 5, |i, j| {
        ((i * 2 + j * 3 + 1) % 5) as f64 - 2.0 + (i == j) as u8 as f64
    })
    .qr()
    .q();
    let plain = basis(&session(&DMatrix::identity(5, 5)), true);
    let turned = basis(&session(&rot), true);
    for (a, b) in [("neutral", "sad"), ("happy", "angry")] {
        let want = &rot * move_between(&plain, a, b);
        let got = move_between(&turned, a, b);
        assert!((got - want).norm() < 1e-6, "{a} -> {b}");
    }
    for (x, y) in plain.persistence.iter().zip(&turned.persistence) {
        assert!((x - y).abs() < 1e-6);
    }
}
