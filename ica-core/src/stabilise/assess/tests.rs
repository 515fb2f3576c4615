use super::*;

#[test]
fn explained_share_of_a_linear_response_is_one_and_of_noise_is_small() {
    let rows: Vec<(SVector<f64, 7>, Vector3<f64>)> = (0..200)
        .map(|i| {
            let t = i as f64 * 0.1;
            let x = SVector::<f64, 7>::from_column_slice(&[
                t.sin() * 20.0,
                t.cos(),
                (2.0 * t).sin(),
                0.01 * (3.0 * t).cos(),
                0.02 * t.sin(),
                0.0,
                1.0,
            ]);
            (x, Vector3::new(2.0 * x[0], -x[1], 0.5 * x[3]))
        })
        .collect();
    let share = explained_share(&rows).expect("solvable");
    assert!((share - 1.0).abs() < 1e-6, "{share}");
}
