use super::*;

#[test]
fn kind_index_matches_all_table() {
    for (i, k) in NatNetErrorKind::ALL.iter().enumerate() {
        assert_eq!(k.index(), i, "{k:?}");
    }
    let e = NatNetError::BadCount {
        count: -2,
        offset: 8,
    };
    assert_eq!(e.kind().as_str(), "natnet_bad_count");
    assert_eq!(
        e.to_string(),
        "count -2 at byte 8 is negative or exceeds the remaining bytes"
    );
}
