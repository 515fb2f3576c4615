use super::*;

#[test]
fn cholesky_solves_a_known_system() {
    // A = [[4, 2], [2, 3]], b = A [1, -2] = [0, -4]; only the upper triangle is read.
    let mut a = vec![4.0, 2.0, f64::NAN, 3.0];
    let mut piv = vec![0.0; 2];
    assert!(cholesky::<Plain>(&mut a, &mut piv, 2));
    assert_eq!(piv, vec![4.0, 2.0]);
    let mut x = vec![0.0; 2];
    let at = vec![a[0], f64::NAN, a[1], a[3]];
    let inv = vec![1.0 / a[0], 1.0 / a[3]];
    solve_factored::<Plain>(&a, &at, &inv, &[0.0, -4.0], &mut x);
    assert!((x[0] - 1.0).abs() < 1e-12 && (x[1] + 2.0).abs() < 1e-12);
    let mut singular = vec![1.0, 1.0, 0.0, 1.0];
    assert!(!cholesky::<Plain>(&mut singular, &mut piv, 2));
    // Packed [4; 2, 3] unpacks to the upper triangle.
    let mut square = vec![0.0; 4];
    unpack(&[4.0, 2.0, 3.0], &mut square, 2);
    assert_eq!(square, vec![4.0, 2.0, 0.0, 3.0]);
}
