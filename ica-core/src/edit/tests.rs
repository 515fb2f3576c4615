use super::*;

#[test]
fn frame_edit_order_is_gain_offset_then_override() {
    let mut e = FrameEdit::identity(3);
    assert!(e.is_identity());
    e.set_gain(0, 2.0).expect("in range");
    e.set_offset(0, 0.5).expect("in range");
    e.set_offset(1, -1.0).expect("in range");
    e.set_override(2, Some(7.0)).expect("in range");
    let mut u = [1.0, 1.0, 1.0];
    e.apply(&mut u).expect("sized for 3");
    assert_eq!(u, [2.5, 0.0, 7.0]);
    assert!(matches!(
        e.set_gain(3, 1.0),
        Err(EditError::ComponentOutOfRange {
            index: 3,
            components: 3
        })
    ));
    assert!(matches!(
        e.set_offset(1, f32::NAN),
        Err(EditError::NonFinite { what: "offset", .. })
    ));
    assert!(matches!(
        e.apply(&mut [0.0; 2]),
        Err(FrameError::Length {
            expected: 3,
            got: 2,
            ..
        })
    ));
    e.reset();
    assert!(e.is_identity());
}

#[test]
fn whole_take_edits() {
    let mut s = DMatrix::from_row_slice(3, 2, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
    translate(&mut s, 1, 10.0).expect("in range");
    assert_eq!(s.column(1).as_slice(), &[12.0, 14.0, 16.0]);
    scale_component(&mut s, 0, -1.0).expect("in range");
    assert_eq!(s.column(0).as_slice(), &[-1.0, -3.0, -5.0]);
    set_component_from(&mut s, 0, &[9.0, 8.0, 7.0]).expect("one per frame");
    assert_eq!(s.column(0).as_slice(), &[9.0, 8.0, 7.0]);
    assert!(matches!(
        set_component_from(&mut s, 0, &[1.0]),
        Err(EditError::SeriesLength {
            expected: 3,
            got: 1
        })
    ));
    let other = DMatrix::from_row_slice(3, 2, &[0.0, -1.0, 0.0, -2.0, 0.0, -3.0]);
    copy_replace(&mut s, &other, 1).expect("aligned");
    assert_eq!(s.column(1).as_slice(), &[-1.0, -2.0, -3.0]);
    assert_eq!(s.column(0).as_slice(), &[9.0, 8.0, 7.0]);
    assert!(translate(&mut s, 2, 1.0).is_err());
}
