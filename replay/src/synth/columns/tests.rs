use super::*;

#[test]
fn infos_follow_the_columns() {
    for k in 1..=MAX_EMOTION_DIMS {
        let l = SourceLayout::new(k).expect("in range");
        let infos = l.source_infos();
        assert_eq!(infos.len(), l.count());
        for i in 0..k {
            assert_eq!(infos[l.emotion(i)].role, "emotion");
            assert_eq!(infos[l.emotion(i)].name, SourceLayout::emotion_name(i));
        }
        assert_eq!(infos[l.brow_raise()].name, "brow_raise");
        assert_eq!(infos[l.blink()].name, "blink");
        assert_eq!(infos[l.head()].name, "head_pitch");
        assert_eq!(infos[l.count() - 1].name, "head_tz");
    }
    let err = SourceLayout::new(4).expect_err("only three fields");
    assert!(err.to_string().contains('4'), "{err}");
    assert!(SourceLayout::new(0).is_err());
}
