use super::*;

#[test]
fn spread_effects_move_every_face_region_and_no_head_marker() {
    let face = FaceGeometry::standard();
    let layout = SourceLayout::new(2).expect("in range");
    let base = super::super::mixing::mixing_matrix(&face, false, layout);
    let mut spread = base.clone();
    add_spread_effects(&mut spread, &face, layout, 4, 1.0);
    let count = layout.count();
    for region in Region::ALL {
        let moved = face.indices(region).iter().any(|&i| {
            (0..3).any(|a| {
                let at = (i * 3 + a) * count + layout.emotion(1);
                (spread[at] - base[at]).abs() > 0.05
            })
        });
        assert_eq!(moved, region != Region::HeadReference, "{region:?}");
    }
}
