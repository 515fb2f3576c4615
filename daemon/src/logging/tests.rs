use super::colour;

#[test]
fn colour_only_on_a_terminal_without_no_color() {
    assert!(colour(true, None));
    assert!(!colour(false, None));
    assert!(!colour(true, Some("1".into())));
    assert!(colour(true, Some("".into())));
}
