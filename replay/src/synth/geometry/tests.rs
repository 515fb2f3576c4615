use super::*;

#[test]
fn standard_face_has_109_unique_well_separated_markers() {
    let face = FaceGeometry::standard();
    assert_eq!(face.markers.len(), MARKER_COUNT);
    let labels = face.labels();
    for (i, l) in labels.iter().enumerate() {
        assert!(!labels[..i].contains(l), "duplicate label {l}");
    }
    for i in 0..face.markers.len() {
        for j in 0..i {
            let (a, b) = (face.markers[i].rest, face.markers[j].rest);
            let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            assert!(d > 5.0, "{} and {} are {d} mm apart", labels[i], labels[j]);
        }
    }
    let xs: Vec<f64> = face.markers.iter().map(|m| m.rest[0]).collect();
    let width =
        xs.iter().cloned().fold(f64::MIN, f64::max) - xs.iter().cloned().fold(f64::MAX, f64::min);
    assert!((130.0..=160.0).contains(&width), "face width {width}");
}
