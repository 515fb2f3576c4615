use super::*;

#[test]
fn cholesky_solves_a_known_system() {
    // A = [[4, 2], [2, 3]] packed lower, b = A [1, -2] = [0, -4]
    let mut a = vec![4.0, 2.0, 3.0];
    let mut piv = vec![0.0; 2];
    assert!(cholesky(&mut a, &mut piv, 2));
    assert_eq!(piv, vec![4.0, 2.0]);
    let mut x = vec![0.0; 2];
    solve_factored(&a, &[0.0, -4.0], &mut x, 2);
    assert!((x[0] - 1.0).abs() < 1e-12 && (x[1] + 2.0).abs() < 1e-12);
    let mut singular = vec![1.0, 1.0, 1.0];
    assert!(!cholesky(&mut singular, &mut piv, 2));
}
