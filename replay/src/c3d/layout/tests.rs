use super::unique_labels;

fn strings(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

#[test]
fn repeated_and_missing_labels_get_suffixes_and_numbers() {
    let raw = strings(&["A", "A", "A_2", "A", "", "B"]);
    let got = unique_labels(&raw, 7);
    assert_eq!(
        got,
        strings(&["A", "A_2", "A_2_2", "A_3", "M005", "B", "M007"])
    );
}

#[test]
fn one_label_over_every_point_of_a_large_file_stays_unique() {
    // A damaged file may repeat one label over the most points a header can hold.
    let raw = vec!["X".to_string(); 65_535];
    let got = unique_labels(&raw, raw.len());
    assert_eq!(got[0], "X");
    assert_eq!(got[1], "X_2");
    assert_eq!(got[65_534], "X_65535");
    let distinct: std::collections::HashSet<_> = got.iter().collect();
    assert_eq!(distinct.len(), got.len());
}
