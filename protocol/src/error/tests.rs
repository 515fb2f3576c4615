use super::*;

#[test]
fn kind_index_matches_all_table() {
    for (i, k) in DecodeErrorKind::ALL.iter().enumerate() {
        assert_eq!(k.index(), i, "{k:?}");
    }
    let e = DecodeError::TooManyMarkers { markers: 9, max: 3 };
    assert_eq!(e.kind().as_str(), "too_many_markers");
    assert_eq!(e.to_string(), "9 markers exceed the buffer's maximum of 3");
}
