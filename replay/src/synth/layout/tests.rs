use super::*;

#[test]
fn the_default_layout_is_the_standard_face() {
    assert_eq!(Layout::default().face(7), FaceGeometry::standard());
}

#[test]
fn layouts_change_count_names_rigid_markers_and_placement() {
    let sparse = Layout {
        markers: MarkerSet::Sparse,
        naming: Naming::Numbered,
        rigid: RigidMarkers::Vicon,
        placement_jitter_mm: 3.0,
    };
    let face = sparse.face(1);
    assert_eq!(face.markers.len(), 45);
    assert_eq!(face.markers[0].label, "M001");
    assert_eq!(face.markers[0].kind, "LFHD");
    let moved = face
        .markers
        .iter()
        .filter(|m| m.rest != m.canonical)
        .count();
    assert_eq!(moved, face.markers.len());
    assert_ne!(sparse.face(2), face, "the seed places the markers");
    let snake = Layout {
        naming: Naming::Snake,
        rigid: RigidMarkers::None,
        ..Layout::default()
    };
    let labels = snake.face(0).labels();
    assert_eq!(labels.len(), 105);
    assert!(labels.contains(&"forehead_07".to_string()));
    assert!(!labels.iter().any(|l| l.starts_with("head")));
    assert_eq!("vicon".parse(), Ok(RigidMarkers::Vicon));
    assert!("helmet".parse::<RigidMarkers>().is_err());
}
