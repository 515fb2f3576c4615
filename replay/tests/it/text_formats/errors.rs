//! Damaged input: one typed error per kind of damage, and no panics.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use replay::{csv, trc, ReadError, Take, WriteError};

use super::{fixture, random_take, read_csv, read_trc, trc_with_row, SMALL_CSV, SMALL_TRC};

#[test]
fn truncated_trc_names_both_frame_counts() {
    let text = std::fs::read_to_string(fixture("NoseMoCap_first60.trc")).unwrap();
    let cut: String = text
        .lines()
        .take(6 + 55)
        .map(|l| format!("{l}\n"))
        .collect();
    let err = read_trc(&cut).unwrap_err();
    assert!(matches!(
        err,
        ReadError::FrameCountMismatch {
            declared: 60,
            found: 55
        }
    ));
    assert_eq!(
        err.to_string(),
        "header declares 60 frames but the data holds 55"
    );
    // A header that undercounts is read as far as it counts, as a C3D header's range is: the
    // rows past it are a recording's last frames, which `emoshift repair` counts (issue 36).
    let extra = format!("{SMALL_TRC}13\t0.03\t1\t2\t3\t4\t5\t6\n");
    assert_eq!(read_trc(&extra).unwrap(), read_trc(SMALL_TRC).unwrap());
}

#[test]
fn trc_row_cut_inside_a_marker_is_a_truncated_row() {
    let text = std::fs::read_to_string(fixture("NoseMoCap_first60.trc")).unwrap();
    let last = text.lines().last().unwrap();
    // Keep frame, time, marker 1 and the x of marker 2: cut just before marker 2's y.
    let keep: Vec<&str> = last.split('\t').take(6).collect();
    let cut = text.replace(last, &keep.join("\t"));
    let err = read_trc(&cut).unwrap_err();
    match &err {
        ReadError::TruncatedRow {
            line,
            marker,
            cells,
        } => {
            assert_eq!((*line, marker.as_str(), *cells), (66, "ForeHead_L", 1));
        }
        other => panic!("expected TruncatedRow, got {other}"),
    }
    // Cut exactly after marker 1 with no final newline: the cut, not missing markers.
    let keep: Vec<&str> = last.split('\t').take(5).collect();
    let cut = text.replace(&format!("{last}\n"), &keep.join("\t"));
    assert!(matches!(
        read_trc(&cut),
        Err(ReadError::TruncatedRow {
            line: 66,
            cells: 0,
            ..
        })
    ));
    // The same short row with its newline means markers 2-41 are missing in that frame.
    let take = read_trc(&format!("{cut}\n")).unwrap();
    assert_eq!(take.frame_missing(59).iter().filter(|&&m| m).count(), 40);
}

#[test]
fn trc_short_rows_trailing_tabs_crlf_and_no_blank_line_are_tolerated() {
    let text = trc_with_row(11, "11\t0.01\t1.5\t2.5\t3.5");
    let take = read_trc(&text).unwrap();
    assert_eq!(take.frame_missing(1), [false, true]);
    let text = trc_with_row(11, "11\t0.01\t1.5\t2.5\t3.5\t4.5\t5.5\t6.5\t\t");
    assert_eq!(read_trc(&text).unwrap(), read_trc(SMALL_TRC).unwrap());
    let crlf = SMALL_TRC.replace("\n\n", "\n").replace('\n', "\r\n");
    assert_eq!(read_trc(&crlf).unwrap(), read_trc(SMALL_TRC).unwrap());
}

#[test]
fn nan_and_blank_cells_mean_missing_in_both_formats() {
    let take = read_trc(&trc_with_row(12, "12\t0.02\tNaN\t3\t4\t5\t\t7")).unwrap();
    assert_eq!(take.frame_missing(2), [true, true]);
    assert_eq!(take.sample(2, 0), None);
    let take = read_csv(&SMALL_CSV.replace("12,0.02,2,3,4", "12,0.02,2,nan,4")).unwrap();
    assert_eq!(take.frame_missing(2), [true, false]);
}

#[test]
fn a_coordinate_past_ten_kilometres_is_corrupt_data_named_by_frame_and_marker() {
    // 9e37 mm: what random bytes in a float field read as.
    for (text, read) in [
        (
            trc_with_row(11, "11\t0.01\t1.5\t2.5\t3.5\t4.5\t9e37\t6.5"),
            read_trc as fn(&str) -> _,
        ),
        (
            SMALL_CSV.replace(
                "11,0.01,1.5,2.5,3.5,4.5,5.5",
                "11,0.01,1.5,2.5,3.5,4.5,9e37",
            ),
            read_csv,
        ),
    ] {
        let err = read(&text).unwrap_err();
        assert!(
            matches!(
                &err,
                ReadError::Invalid(replay::TakeError::Implausible { frame: 1, marker, value })
                    if marker == "Chin" && *value == 9e37
            ),
            "{err}"
        );
        assert!(err.to_string().contains("past 10 km"), "{err}");
    }
    // 9.99 km is still a number a file may hold (a take in metres read as millimetres).
    assert!(read_trc(&trc_with_row(
        11,
        "11\t0.01\t1.5\t2.5\t3.5\t4.5\t9990000\t6.5"
    ))
    .is_ok());
}

#[test]
fn bad_cells_name_line_column_and_marker() {
    let cases = [
        (
            read_trc(&trc_with_row(11, "11\t0.01\t1.5\t2.5\t3.5\t4.5\tabc\t6.5")),
            8,
            7,
            "Chin y",
        ),
        (
            read_trc(&trc_with_row(12, "12\t0.02\t2\t3\tinf\t5\t6\t7")),
            9,
            5,
            "Nose Tip z",
        ),
        (
            read_trc(&trc_with_row(11, "11\tsoon\t1\t2\t3\t4\t5\t6")),
            8,
            2,
            "Time",
        ),
        (
            read_trc(&trc_with_row(11, "x1\t0.01\t1\t2\t3\t4\t5\t6")),
            8,
            1,
            "Frame#",
        ),
        (
            read_csv(&SMALL_CSV.replace("5.5", "-Infinity")),
            3,
            7,
            "Chin y",
        ),
        (
            read_csv(&SMALL_CSV.replace("1.5,2.5", "1.5,2..5")),
            3,
            4,
            "Nose Tip y",
        ),
    ];
    for (result, want_line, want_column, want_field) in cases {
        match result {
            Err(ReadError::BadCell {
                line,
                column,
                field,
                ..
            }) => assert_eq!(
                (line, column, field.as_str()),
                (want_line, want_column, want_field)
            ),
            other => panic!("expected BadCell at {want_line}:{want_column}, got {other:?}"),
        }
    }
    let err = read_trc(&trc_with_row(12, "12\t0.02\t2\t3\tinf\t5\t6\t7")).unwrap_err();
    assert_eq!(
        err.to_string(),
        "line 9, column 5 (Nose Tip z): expected a finite number, an empty cell or NaN, found \"inf\""
    );
}

#[test]
fn wrong_column_counts_and_frame_gaps_are_typed_errors() {
    let long = trc_with_row(11, "11\t0.01\t1\t2\t3\t4\t5\t6\t7");
    assert!(matches!(
        read_trc(&long),
        Err(ReadError::ColumnCount {
            line: 8,
            expected: 8,
            found: 9
        })
    ));
    let short = SMALL_CSV.replace("11,0.01,1.5,2.5,3.5,4.5,5.5,6.5", "11,0.01,1.5,2.5,3.5");
    assert!(matches!(
        read_csv(&short),
        Err(ReadError::ColumnCount {
            line: 3,
            expected: 8,
            found: 5
        })
    ));
    let gap = trc_with_row(11, "13\t0.01\t1\t2\t3\t4\t5\t6");
    assert!(matches!(
        read_trc(&gap),
        Err(ReadError::FrameGap {
            line: 8,
            expected: 11,
            found: 13
        })
    ));
    let gap = SMALL_CSV.replace("\n12,", "\n11,");
    assert!(matches!(
        read_csv(&gap),
        Err(ReadError::FrameGap {
            line: 4,
            expected: 12,
            found: 11
        })
    ));
    let bad_header = SMALL_CSV.replace("Chin_y", "Chim_y");
    assert!(matches!(
        read_csv(&bad_header),
        Err(ReadError::BadCell {
            line: 1,
            column: 7,
            ..
        })
    ));
}

#[test]
fn labels_a_format_cannot_hold_are_refused_before_writing() {
    let mut take = Take::new(vec!["ok".into(), "a,b".into()], 60.0, 1);
    take.push_frame(&[0.0; 6], &[false, false]);
    let mut out = Vec::new();
    let err = csv::write(&take, &mut out).unwrap_err();
    assert!(
        matches!(err, WriteError::LabelUnrepresentable { forbidden: ',', .. }),
        "{err}"
    );
    assert!(out.is_empty());
    // The comma is fine in TRC; a tab is not.
    trc::write(&take, &mut out).unwrap();
    take.labels[1] = "a\tb".into();
    out.clear();
    let err = trc::write(&take, &mut out).unwrap_err();
    assert!(
        matches!(
            err,
            WriteError::LabelUnrepresentable {
                forbidden: '\t',
                ..
            }
        ),
        "{err}"
    );
    assert!(out.is_empty());
}

/// Damaged files of every shape return an error or a valid take, never panic.
#[test]
fn damaged_input_never_panics() {
    let mut rng = ChaCha8Rng::seed_from_u64(2024);
    let mut csv_bytes = Vec::new();
    csv::write(&random_take(5, 6), &mut csv_bytes).unwrap();
    let sources = [
        SMALL_TRC.as_bytes().to_vec(),
        SMALL_CSV.as_bytes().to_vec(),
        csv_bytes,
    ];
    let noise = [
        b'\t', b',', b'\n', b'\r', b'#', b'-', b'.', b'e', b'9', 0xff, b'_', b' ',
    ];
    for round in 0..600 {
        let mut bytes = sources[round % 3].clone();
        for _ in 0..rng.random_range(1..4) {
            if bytes.is_empty() {
                break;
            }
            let at = rng.random_range(0..bytes.len());
            match rng.random_range(0..4) {
                0 => bytes[at] = noise[rng.random_range(0..noise.len())],
                1 => {
                    bytes.remove(at);
                }
                2 => bytes.insert(at, noise[rng.random_range(0..noise.len())]),
                _ => bytes.truncate(at.max(1)),
            }
        }
        for take in [trc::read(&bytes[..]), csv::read(&bytes[..])]
            .into_iter()
            .flatten()
        {
            take.validate().unwrap();
        }
    }
}
