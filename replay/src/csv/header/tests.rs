use super::*;

#[test]
fn labels_split_at_the_last_underscore() {
    let labels = parse_header(
        1,
        "frame,time,Lip_Upper_x,Lip_Upper_y,Lip_Upper_z,Chin_X,Chin_Y,Chin_Z",
    )
    .unwrap();
    assert_eq!(
        labels,
        (vec!["Lip_Upper".to_string(), "Chin".to_string()], 0)
    );
    let quoted = parse_header(
        1,
        "\"frame\", \"time\", \"Brow L_x\",\"Brow L_y\",\"Brow L_z\"",
    );
    assert_eq!(quoted.unwrap().0, ["Brow L"]);
    let timed = parse_header(1, "frame,time,timecode,A_x,A_y,A_z").unwrap();
    assert_eq!(timed, (vec!["A".to_string()], 1));
}

#[test]
fn axis_order_and_label_continuity_are_checked() {
    let err = parse_header(3, "frame,time,A_x,A_z,A_y").unwrap_err();
    assert!(
        matches!(
            err,
            ReadError::BadCell {
                line: 3,
                column: 4,
                ..
            }
        ),
        "{err}"
    );
    let err = parse_header(3, "frame,time,A_x,B_y,B_z").unwrap_err();
    assert!(matches!(err, ReadError::BadCell { column: 4, .. }), "{err}");
    let err = parse_header(3, "frame,time,A_x,A_y").unwrap_err();
    assert!(matches!(err, ReadError::BadHeader { line: 3, .. }), "{err}");
    let err = parse_header(3, "time,frame,A_x,A_y,A_z").unwrap_err();
    assert!(matches!(err, ReadError::BadHeader { .. }), "{err}");
}

#[test]
fn comments_set_rate_and_units_and_ignore_prose() {
    let mut meta = Meta::default();
    parse_comment(1, "# exported by hand: rate_hz=119.88 units=cm", &mut meta).unwrap();
    assert_eq!(meta.rate_hz, Some(119.88));
    assert_eq!(meta.units, Some(Units::Centimetres));
    assert!(parse_comment(1, "# rate_hz=-5", &mut meta).is_err());
    assert!(matches!(
        parse_comment(1, "#units=furlong", &mut meta),
        Err(ReadError::UnknownUnits(u)) if u == "furlong"
    ));
}
