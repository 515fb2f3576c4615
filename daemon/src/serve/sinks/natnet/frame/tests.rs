use super::*;

#[test]
fn labels_lose_only_their_own_markersets_prefix() {
    assert_eq!(bare("Face", "Face:BrowL"), "BrowL");
    assert_eq!(bare("Face", "Other:BrowL"), "Other:BrowL");
    assert_eq!(bare("Face", "FaceBrowL"), "FaceBrowL");
    assert_eq!(bare("Face", "Face:"), "Face:");
    assert_eq!(bare("127.0.0.1:9/0", "BrowL"), "BrowL");
}
