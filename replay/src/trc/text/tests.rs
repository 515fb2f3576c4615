use super::*;

#[test]
fn samples_blank_nan_number_and_rejects() {
    assert_eq!(parse_sample(""), Ok(Sample::Missing));
    assert_eq!(parse_sample("  "), Ok(Sample::Missing));
    assert_eq!(parse_sample("NaN"), Ok(Sample::Missing));
    assert_eq!(parse_sample("nan"), Ok(Sample::Missing));
    assert_eq!(parse_sample(" -1.5e2 "), Ok(Sample::Value(-150.0)));
    assert!(parse_sample("inf").is_err());
    assert!(parse_sample("-Infinity").is_err());
    assert!(parse_sample("1.2.3").is_err());
    assert!(parse_sample("abc").is_err());
}

#[test]
fn frame_numbers_accept_integral_floats_only() {
    assert_eq!(parse_frame_number("12"), Some(12));
    assert_eq!(parse_frame_number("-3"), Some(-3));
    assert_eq!(parse_frame_number("12.0"), Some(12));
    assert_eq!(parse_frame_number("12.5"), None);
    assert_eq!(parse_frame_number("x"), None);
    assert_eq!(parse_frame_number("1e300"), None);
}

#[test]
fn lines_strip_crlf_and_number_from_one() {
    let mut lines = Lines::new("a\r\n\r\n  \nb".as_bytes());
    assert_eq!(lines.next_line().unwrap(), Some((1, "a")));
    assert_eq!(lines.next_non_blank().unwrap(), Some((4, "b")));
    assert_eq!(lines.next_line().unwrap(), None);
    let mut bom = Lines::new("\u{feff}frame,time\n\u{feff}x".as_bytes());
    assert_eq!(bom.next_line().unwrap(), Some((1, "frame,time")));
    assert_eq!(bom.next_line().unwrap(), Some((2, "\u{feff}x")));
}

#[test]
fn lines_report_bad_utf8_with_its_line() {
    let mut lines = Lines::new(&b"ok\n\xff\xfe\n"[..]);
    assert!(lines.next_line().unwrap().is_some());
    match lines.next_line() {
        Err(ReadError::NotUtf8 { line }) => assert_eq!(line, 2),
        other => panic!("expected NotUtf8, got {other:?}"),
    }
}

#[test]
fn written_samples_read_back_exactly() {
    for v in [0.0f32, -0.1, 143.5201, 1234.5679, 1.0e-7, -98765.43] {
        let mut s = String::new();
        push_sample(&mut s, v);
        assert_eq!(s.parse::<f32>().unwrap(), v, "{s}");
    }
}
