use super::*;

const HEAD: &str = "PathFileType\t4\t(X/Y/Z)\tx.trc\n\
    DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames\n\
    120\t120\t2\t2\tcm\t120\t5\t2\n\
    Frame#\tTime\tLip Upper\t\t\tChin\t\t\t\n\
    \t\tX1\tY1\tZ1\tX2\tY2\tZ2\n";

#[test]
fn parses_fields_names_and_units() {
    let mut lines = Lines::new(HEAD.as_bytes());
    let h = read_header(&mut lines).unwrap();
    assert_eq!(h.rate_hz, 120.0);
    assert_eq!(h.num_frames, 2);
    assert_eq!(h.units, Units::Centimetres);
    assert_eq!(h.labels, ["Lip Upper", "Chin"]);
    assert_eq!(h.start_frame, Some(5));
    assert_eq!(lines.next_number(), 6);
}

#[test]
fn misaligned_names_are_rejected() {
    let text = HEAD.replace("Lip Upper\t\t\tChin", "Lip Upper\tChin\t\t");
    let err = read_header(&mut Lines::new(text.as_bytes())).unwrap_err();
    assert!(matches!(err, ReadError::BadHeader { line: 4, .. }), "{err}");
}

#[test]
fn marker_count_must_match_names() {
    let text = HEAD.replace("120\t120\t2\t2", "120\t120\t2\t3");
    let err = read_header(&mut Lines::new(text.as_bytes())).unwrap_err();
    assert!(matches!(
        err,
        ReadError::MarkerCountMismatch {
            declared: 3,
            found: 2
        }
    ));
}

#[test]
fn bad_rate_names_its_cell() {
    let text = HEAD.replace("120\t120\t2", "fast\t120\t2");
    let err = read_header(&mut Lines::new(text.as_bytes())).unwrap_err();
    match err {
        ReadError::BadCell {
            line,
            column,
            ref field,
            ..
        } => assert_eq!((line, column, field.as_str()), (3, 1, "DataRate")),
        other => panic!("expected BadCell, got {other}"),
    }
}

#[test]
fn missing_line_is_unexpected_end() {
    let text: String = HEAD.lines().take(3).map(|l| format!("{l}\n")).collect();
    let err = read_header(&mut Lines::new(text.as_bytes())).unwrap_err();
    assert!(
        matches!(err, ReadError::UnexpectedEnd { line: 4, .. }),
        "{err}"
    );
}
