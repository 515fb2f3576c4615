use super::*;
use proptest::prelude::*;

/// Cells made of the characters a row's splitting and trimming must get right: separators,
/// ASCII and Unicode whitespace (U+000B is whitespace to `str::trim` and not to
/// `trim_ascii`), digits and a multi-byte letter.
fn row_text() -> impl Strategy<Value = String> {
    let pieces = prop::sample::select(vec![
        "\t", ",", " ", "\u{b}", "\u{a0}", "\u{3000}", "\r", "1", "-2.5", "e3", "NaN", "é", "",
    ]);
    prop::collection::vec(pieces, 0..24).prop_map(|p| p.concat())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2_000))]

    #[test]
    fn cells_split_and_trim_as_std_does(row in row_text()) {
        for sep in [b'\t', b','] {
            let ours = split_cells(&row, sep, 4);
            let std: Vec<&str> = row.split(char::from(sep)).collect();
            prop_assert_eq!(&ours, &std);
            for cell in ours {
                prop_assert_eq!(trim(cell), cell.trim());
                prop_assert_eq!(parse_sample(cell), parse_sample_std(cell));
            }
        }
    }
}

/// [`parse_sample`] as it was written with std's `trim`.
fn parse_sample_std(cell: &str) -> Result<Sample, &'static str> {
    match cell.trim() {
        "" => Ok(Sample::Missing),
        t => match t.parse::<f64>() {
            Ok(v) if v.is_nan() => Ok(Sample::Missing),
            Ok(v) if v.is_finite() => Ok(Sample::Value(v)),
            _ => Err(EXPECTED_SAMPLE),
        },
    }
}

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
