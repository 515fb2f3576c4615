//! TRC and CSV: real files, round trips, and a typed error for each kind of damage.
#![allow(clippy::unwrap_used)] // a failed unwrap is a failed test

use std::path::{Path, PathBuf};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use replay::{csv, trc, Format, ReadError, Take, Units};

/// Damaged input: one typed error per kind of damage, and no panics.
mod errors;

pub(crate) fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

/// Three frames, two markers, numbered from 10; data rows are lines 7-9.
pub(crate) const SMALL_TRC: &str = "PathFileType\t4\t(X/Y/Z)\tsmall.trc\n\
DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames\n\
100\t100\t3\t2\tmm\t100\t10\t3\n\
Frame#\tTime\tNose Tip\t\t\tChin\t\t\t\n\
\t\tX1\tY1\tZ1\tX2\tY2\tZ2\n\
\n\
10\t0.00\t1\t2\t3\t4\t5\t6\n\
11\t0.01\t1.5\t2.5\t3.5\t4.5\t5.5\t6.5\n\
12\t0.02\t2\t3\t4\t5\t6\t7\n";

/// The same take as CSV, without a rate comment; data rows are lines 2-4.
pub(crate) const SMALL_CSV: &str =
    "frame,time,Nose Tip_x,Nose Tip_y,Nose Tip_z,Chin_x,Chin_y,Chin_z\n\
10,0.00,1,2,3,4,5,6\n\
11,0.01,1.5,2.5,3.5,4.5,5.5,6.5\n\
12,0.02,2,3,4,5,6,7\n";

pub(crate) fn read_trc(text: &str) -> Result<Take, ReadError> {
    trc::read(text.as_bytes())
}

pub(crate) fn read_csv(text: &str) -> Result<Take, ReadError> {
    csv::read(text.as_bytes())
}

/// `SMALL_TRC` with one data row (frame 10, 11 or 12) replaced.
pub(crate) fn trc_with_row(frame: i64, row: &str) -> String {
    let prefix = format!("{frame}\t");
    SMALL_TRC
        .lines()
        .map(|l| if l.starts_with(&prefix) { row } else { l })
        .map(|l| format!("{l}\n"))
        .collect()
}

#[test]
fn real_excerpt_loads_through_format_dispatch() {
    let take = replay::load(&fixture("NoseMoCap_first60.trc")).unwrap();
    assert_eq!((take.n_frames(), take.n_markers()), (60, 41));
    assert_eq!((take.rate_hz, take.first_frame), (60.0, 1));
    assert_eq!(take.source_units, Units::Millimetres);
    assert_eq!(take.labels[0], "ForeHead_M");
    assert_eq!(take.labels[40], "Chin_L2");
    assert!(take.missing.iter().all(|&m| !m));
    // First and last row of the excerpt, as printed in the file.
    assert_eq!(take.sample(0, 0), Some([143.5201, 842.2137, 29.0542]));
    assert_eq!(take.sample(59, 0), Some([141.1453, 840.4015, 36.6570]));
}

#[test]
fn animface_takes_load_with_their_documented_frame_counts() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/animface-rom");
    if !dir.exists() {
        eprintln!(
            "{} absent: only the committed excerpt is checked",
            dir.display()
        );
        return;
    }
    // Walk the folder so a new or replaced take that fails to load is noticed too.
    let mut found = Vec::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "trc") {
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            let take = replay::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(
                (take.n_markers(), take.rate_hz, take.first_frame),
                (41, 60.0, 1),
                "{name}"
            );
            assert!(take.missing.iter().all(|&m| !m), "{name} has gaps");
            found.push((name, take.n_frames()));
        }
    }
    found.sort();
    let expected = [
        ("CheeksMoCap.trc", 1499),
        ("EyebrowsMoCap.trc", 902),
        ("JawMoCap.trc", 1590),
        ("NoseMoCap.trc", 962),
    ];
    let expected: Vec<(String, usize)> = expected.iter().map(|&(n, f)| (n.into(), f)).collect();
    assert_eq!(found, expected, "frame counts per take (SOURCE.txt)");
    // A whole real take survives both writers exactly.
    let nose = replay::load(&dir.join("NoseMoCap.trc")).unwrap();
    for format in [Format::Trc, Format::Csv] {
        let mut bytes = Vec::new();
        replay::write_as(format, &nose, &mut bytes).unwrap();
        let back = match format {
            Format::Trc => trc::read(&bytes[..]),
            _ => csv::read(&bytes[..]),
        };
        assert_eq!(back.unwrap(), nose, "{format:?}");
    }
}

/// A seeded take with awkward labels, ~10% gaps, a fully missing frame, a last marker missing in
/// the last frame, a first frame far from 1 and an NTSC rate.
pub(crate) fn random_take(seed: u64, frames: usize) -> Take {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let labels = ["Lip Upper", "Brow_L_inner", "Chin", "ear-R (2)"];
    let mut take = Take::new(labels.map(String::from).to_vec(), 120_000.0 / 1001.0, -37);
    let n = labels.len();
    for f in 0..frames {
        let xyz: Vec<f32> = (0..3 * n)
            .map(|_| rng.random_range(-2000.0..2000.0))
            .collect();
        let mut gone: Vec<bool> = (0..n).map(|_| rng.random_bool(0.1)).collect();
        if f == 3 {
            gone.fill(true);
        }
        if f == frames - 1 {
            gone[n - 1] = true;
        }
        take.push_frame(&xyz, &gone);
    }
    take
}

#[test]
fn trc_round_trip_is_exact_with_gaps_and_odd_numbering() {
    let take = random_take(7, 50);
    let mut bytes = Vec::new();
    trc::write(&take, &mut bytes).unwrap();
    let back = trc::read(&bytes[..]).unwrap();
    assert_eq!(back, take);
    // Missing samples are empty cells: frame 3 (line 10) has nothing after its time.
    let text = String::from_utf8(bytes).unwrap();
    let row = text.lines().nth(9).unwrap();
    assert!(row.starts_with("-34\t0.025025\t\t\t"), "{row:?}");
}

#[test]
fn csv_round_trip_is_exact_and_keeps_rate_of_a_single_frame() {
    for frames in [50, 1] {
        let take = random_take(11, frames.max(5));
        let take = if frames == 1 {
            first_frames(&take, 1)
        } else {
            take
        };
        let mut bytes = Vec::new();
        csv::write(&take, &mut bytes).unwrap();
        assert_eq!(csv::read(&bytes[..]).unwrap(), take, "{frames} frame(s)");
    }
}

fn first_frames(take: &Take, frames: usize) -> Take {
    let mut out = Take::new(take.labels.clone(), take.rate_hz, take.first_frame);
    for f in 0..frames {
        out.push_frame(take.frame(f), take.frame_missing(f));
    }
    out
}

#[test]
fn writers_emit_the_documented_layouts() {
    let mut take = Take::new(vec!["A b".into(), "C_d".into()], 120.0, 5);
    take.push_frame(&[1.0, 2.5, -3.0, 0.1, 0.2, 0.3], &[false, true]);
    take.push_frame(&[1.25, 2.0, 3.0, 10.0, 20.0, 30.0], &[false, false]);
    let mut trc_out = Vec::new();
    trc::write(&take, &mut trc_out).unwrap();
    let expected_trc = "PathFileType\t4\t(X/Y/Z)\ttake.trc\n\
DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames\n\
120\t120\t2\t2\tmm\t120\t5\t2\n\
Frame#\tTime\tA b\t\t\tC_d\t\t\n\
\t\tX1\tY1\tZ1\tX2\tY2\tZ2\n\
\n\
5\t0.000000\t1\t2.5\t-3\t\t\t\n\
6\t0.008333\t1.25\t2\t3\t10\t20\t30\n";
    assert_eq!(String::from_utf8(trc_out).unwrap(), expected_trc);
    let mut csv_out = Vec::new();
    csv::write(&take, &mut csv_out).unwrap();
    let expected_csv = "# rate_hz=120 units=mm\n\
frame,time,A b_x,A b_y,A b_z,C_d_x,C_d_y,C_d_z\n\
5,0.000000,1,2.5,-3,,,\n\
6,0.008333,1.25,2,3,10,20,30\n";
    assert_eq!(String::from_utf8(csv_out).unwrap(), expected_csv);
}

#[test]
fn csv_rate_is_derived_from_time_when_not_declared() {
    let take = read_csv(SMALL_CSV).unwrap();
    assert_eq!(
        (take.rate_hz, take.first_frame, take.n_frames()),
        (100.0, 10, 3)
    );
    // 120 Hz written with 6 decimals (0.008333 steps) still comes back as exactly 120.
    let mut bytes = Vec::new();
    csv::write(&random_take(3, 2), &mut bytes).unwrap();
    let text = String::from_utf8(bytes)
        .unwrap()
        .replace("# rate_hz=119.88011988011988 ", "# ");
    assert_eq!(read_csv(&text).unwrap().rate_hz, 120_000.0 / 1001.0);
    let one_frame: String = SMALL_CSV
        .lines()
        .take(2)
        .map(|l| format!("{l}\n"))
        .collect();
    assert!(matches!(
        read_csv(&one_frame),
        Err(ReadError::NoRate { frames: 1 })
    ));
    let stalled = SMALL_CSV.replace("11,0.01,", "11,0.00,");
    let err = read_csv(&stalled).unwrap_err();
    assert!(
        matches!(err, ReadError::UnevenTime { line: 3, .. }),
        "{err}"
    );
}

#[test]
fn csv_comment_units_convert_to_mm() {
    let text = format!("# rate_hz=50 units=cm\n{SMALL_CSV}");
    let take = read_csv(&text).unwrap();
    assert_eq!(
        (take.rate_hz, take.source_units),
        (50.0, Units::Centimetres)
    );
    assert_eq!(take.sample(1, 0), Some([15.0, 25.0, 35.0]));
}

#[test]
fn trc_units_convert_to_mm_and_unknown_units_are_rejected() {
    let take = read_trc(&SMALL_TRC.replace("\tmm\t", "\tm\t")).unwrap();
    assert_eq!(take.source_units, Units::Metres);
    assert_eq!(take.sample(1, 1), Some([4500.0, 5500.0, 6500.0]));
    let err = read_trc(&SMALL_TRC.replace("\tmm\t", "\tinches\t")).unwrap_err();
    assert!(
        matches!(&err, ReadError::UnknownUnits(u) if u == "inches"),
        "{err}"
    );
}

#[test]
fn empty_takes_round_trip_with_their_first_frame_in_trc() {
    let take = first_frames(&random_take(1, 5), 0);
    let mut bytes = Vec::new();
    trc::write(&take, &mut bytes).unwrap();
    assert_eq!(trc::read(&bytes[..]).unwrap(), take);
    bytes.clear();
    csv::write(&take, &mut bytes).unwrap();
    let back = csv::read(&bytes[..]).unwrap();
    // CSV numbers frames only in its rows, so an empty one starts at frame 1.
    assert_eq!(
        (back.n_frames(), back.rate_hz, back.first_frame),
        (0, take.rate_hz, 1)
    );
}

/// A file without newlines (a binary renamed .csv, a comment that never ends) is refused at
/// 16 MiB, not held whole however large it is: by the readers, and by `repair`'s inspection.
#[test]
fn a_line_without_end_is_refused_at_16_mib() {
    use std::io::Read;
    let endless = |first: u8| std::io::repeat(first).take((16 << 20) + 1);
    for (what, got) in [
        ("csv comment", csv::read(endless(b'#'))),
        ("csv header", csv::read(endless(b'f'))),
        ("trc header", trc::read(endless(b'P'))),
    ] {
        match got {
            Err(ReadError::LineTooLong {
                line: 1,
                max_mib: 16,
            }) => {}
            other => panic!("{what}: {other:?}"),
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("comments.csv");
    let mut file = std::fs::File::create(&path).unwrap();
    std::io::copy(&mut endless(b'#'), &mut file).unwrap();
    let err = replay::repair::inspect(&path).expect_err("not a take");
    let cause = std::error::Error::source(&err).map(ToString::to_string);
    assert!(cause.unwrap_or_default().contains("over 16 MiB"), "{err:?}");
}
