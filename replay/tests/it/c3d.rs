//! C3D reading and writing: round trips, the in-repo fixtures, damaged input.

use std::path::{Path, PathBuf};

use replay::c3d::{self, C3dError, C3dLimitError, Decoder, Processor};
use replay::{ReadError, Take, WriteError};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

fn read_fixture(name: &str) -> (Take, c3d::C3dInfo) {
    let bytes = std::fs::read(fixture(name)).expect("fixture present");
    c3d::read_with_info(&bytes).expect("fixture reads")
}

/// A take with smooth motion and a deterministic gap pattern, including whole-frame gaps and a
/// marker missing at the first and last frames.
fn synthetic(markers: usize, frames: usize, first_frame: i64, rate_hz: f64) -> Take {
    let labels = (0..markers).map(|m| format!("marker_{m:03}")).collect();
    let mut take = Take::new(labels, rate_hz, first_frame);
    for f in 0..frames {
        let mut xyz = Vec::with_capacity(markers * 3);
        let mut gone = Vec::with_capacity(markers);
        for m in 0..markers {
            let t = f as f32 / rate_hz as f32;
            xyz.extend([
                100.0 * m as f32 + 12.345 * (t * 1.3 + m as f32).sin(),
                -250.5 + 30.0 * (t * 0.7).cos(),
                1500.125 + 0.001 * f as f32,
            ]);
            gone.push((f * 7 + m * 3) % 11 == 0 || (m == 1 && (f == 0 || f + 1 == frames)));
        }
        take.push_frame(&xyz, &gone);
    }
    take
}

fn write_bytes(take: &Take) -> Vec<u8> {
    let mut out = Vec::new();
    c3d::write(take, &mut out).expect("take is writable");
    out
}

fn assert_same(a: &Take, b: &Take, tol_mm: f32) {
    assert_eq!(a.labels, b.labels);
    assert_eq!(a.rate_hz, b.rate_hz);
    assert_eq!(a.first_frame, b.first_frame);
    assert_eq!(a.n_frames(), b.n_frames());
    assert_eq!(a.missing, b.missing, "missing masks differ");
    let worst = a
        .positions
        .iter()
        .zip(&b.positions)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0f32, f32::max);
    assert!(worst <= tol_mm, "positions differ by {worst} mm");
}

/// Past 256 frames c3dio reads a copy holding a sample of them (first and last included,
/// padded to a whole block): it still confirms the decoding, and the take is every frame.
#[test]
fn a_long_take_is_cross_checked_on_a_sample_and_read_whole() {
    let take = synthetic(9, 2_001, 5, 120.0);
    let (back, info) = c3d::read_with_info(&write_bytes(&take)).expect("own output reads");
    assert_eq!(info.decoder, Decoder::C3dio, "{info:?}");
    assert_eq!(back.n_frames(), 2_001);
    assert_same(&take, &back, 1e-3);
}

#[test]
fn round_trip_keeps_labels_rate_first_frame_values_and_gaps() {
    let mut take = synthetic(12, 240, 17, 119.88);
    take.labels[3] = "a_label_much_longer_than_the_usual_thirty_two_characters".into();
    let bytes = write_bytes(&take);
    assert_eq!(bytes.len() % 512, 0, "whole blocks");
    let (back, info) = c3d::read_with_info(&bytes).expect("own output reads");
    assert_eq!(
        info.decoder,
        Decoder::C3dio,
        "c3dio accepts our files: {info:?}"
    );
    assert_eq!(info.processor, Processor::Intel);
    assert!(info.float && info.warnings.is_empty());
    assert_same(&take, &back, 1e-3);
    assert!(back.missing.iter().any(|&m| m), "the take has gaps");
}

#[test]
fn more_than_255_markers_use_labels2() {
    let take = synthetic(300, 3, 1, 60.0);
    let back = c3d::read(&write_bytes(&take)[..]).expect("reads");
    assert_same(&take, &back, 1e-3);
}

#[test]
fn more_than_65535_frames_round_trip_through_trial_fields() {
    let take = synthetic(1, 70_000, 5, 240.0);
    let back = c3d::read(&write_bytes(&take)[..]).expect("reads");
    assert_same(&take, &back, 1e-3);
}

#[test]
fn takes_c3d_cannot_hold_are_refused_with_the_reason() {
    let empty = Take::new(vec!["a".into()], 100.0, 1);
    assert!(matches!(
        c3d::write(&empty, &mut Vec::new()),
        Err(WriteError::C3dLimit(C3dLimitError::NoFrames))
    ));
    let mut long = synthetic(2, 2, 1, 100.0);
    long.labels[0] = "x".repeat(256);
    assert!(matches!(
        c3d::write(&long, &mut Vec::new()),
        Err(WriteError::C3dLimit(C3dLimitError::LabelTooLong {
            len: 256,
            ..
        }))
    ));
    let negative = synthetic(2, 2, -3, 100.0);
    let err = c3d::write(&negative, &mut Vec::new()).expect_err("negative first frame");
    assert_eq!(
        err.to_string(),
        "c3d frame numbers cannot be negative, take starts at -3: write TRC or CSV, or renumber \
         the take"
    );
}

/// A live source's frame numbers pass 65535 after nine minutes at 120 Hz (Motive's run from its
/// start): such a take is stored numbered from 1, so every reader counts its frames, with its
/// true first frame in EMOSHIFT:FIRST_FRAME, which emoshift reads back.
#[test]
fn a_first_frame_past_65535_keeps_its_numbers_and_the_header_counts_from_1() {
    for (first, frames) in [(150_000, 40), (65_530, 12), (70_000, 70_000)] {
        let take = synthetic(3, frames, first, 120.0);
        let bytes = write_bytes(&take);
        let word = |at: usize| u16::from_le_bytes([bytes[at], bytes[at + 1]]);
        let header_first = if first > 65_535 { 1 } else { first as u16 };
        assert_eq!(word(6), header_first, "header first frame of {first}");
        let header_last = (i64::from(header_first) + frames as i64 - 1).min(65_535);
        assert_eq!(
            i64::from(word(8)),
            header_last,
            "header last frame of {first}"
        );
        let back = c3d::read(&bytes[..]).expect("reads");
        assert_eq!(back.first_frame, first);
        assert_same(&take, &back, 1e-3);
    }
}

#[test]
fn facial_sing_reads_with_its_gaps() {
    let (take, info) = read_fixture("Facial-Sing.c3d");
    assert_eq!(info.decoder, Decoder::C3dio);
    assert_eq!((take.n_markers(), take.n_frames()), (38, 3000));
    assert_eq!((take.first_frame, take.rate_hz), (1, 100.0));
    assert_eq!(take.source_units, replay::Units::Millimetres);
    let missing = take.missing_per_marker();
    assert_eq!(missing.iter().sum::<usize>(), 3716);
    // Per marker, in file order (root-1..6, section1-1 ... section14-3, Unlabeled1): every
    // sample flagged by residual -1 has xyz exactly 0 in this file, so both rules agree.
    let expected = [
        0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 33, 0, 42, 110, 254, 0, 257, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
        0, 0, 0, 0, 55, 0, 0, 0, 0, 2965,
    ];
    assert_eq!(missing, expected);
    let unlabeled = take.marker_index("Unlabeled1").expect("Unlabeled1 marker");
    assert!(missing[unlabeled] > 2500, "Unlabeled1 is mostly missing");
}

#[test]
fn eb015_processor_and_storage_variants_decode_identically() {
    let (pi, info) = read_fixture("Eb015pi.c3d");
    assert_eq!((info.processor, info.float), (Processor::Intel, false));
    assert_eq!(
        (pi.n_markers(), pi.n_frames(), pi.first_frame),
        (26, 450, 1)
    );
    assert_eq!(pi.rate_hz, 50.0);
    assert_eq!(pi.missing.iter().filter(|&&m| m).count(), 226);
    for (name, processor) in [
        ("Eb015vr.c3d", Processor::Dec),
        ("Eb015sr.c3d", Processor::Mips),
    ] {
        let (other, info) = read_fixture(name);
        assert_eq!((info.processor, info.float), (processor, true), "{name}");
        assert_same(&pi, &other, 1e-3);
    }
}

#[test]
fn moved_parameter_and_data_blocks_read_like_the_original() {
    let (pi, _) = read_fixture("Eb015pi.c3d");
    let (moved, info) = read_fixture("TESTBPI.c3d");
    assert_eq!(info.decoder, Decoder::C3dio);
    assert_same(&pi, &moved, 0.0);
}

#[test]
fn truncated_files_are_errors_not_panics() {
    let bytes = std::fs::read(fixture("Eb015pi.c3d")).expect("fixture");
    // (The last block is padding: cutting inside it loses no frame, so those cuts stay readable.)
    for cut in [
        0,
        1,
        100,
        511,
        512,
        515,
        1024,
        5000,
        10_000,
        bytes.len() / 2,
    ] {
        match c3d::read(&bytes[..cut]) {
            Ok(_) => panic!("a file cut at byte {cut} must not read"),
            Err(e) => assert!(!e.to_string().is_empty()),
        }
    }
    let err = c3d::read(&bytes[..bytes.len() - 1000]).expect_err("short data");
    assert!(
        matches!(err, ReadError::C3d(C3dError::Truncated { .. })),
        "{err}"
    );
}

#[test]
fn garbage_is_an_error_not_a_panic() {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let good = std::fs::read(fixture("Eb015pi.c3d")).expect("fixture");
    for round in 0..200 {
        let mut bytes: Vec<u8> = if round % 2 == 0 {
            (0..(next() % 20_000) as usize)
                .map(|_| next() as u8)
                .collect()
        } else {
            // Keep a valid-looking header so the parser goes deeper before it hits noise.
            let mut b = good[..good.len().min(8192)].to_vec();
            for _ in 0..20 {
                let i = (next() as usize) % b.len();
                b[i] = next() as u8;
            }
            b
        };
        if round % 4 == 1 {
            bytes[1] = 0x50;
        }
        let _ = c3d::read(&bytes[..]);
    }
    assert!(matches!(
        c3d::read(&b"not a c3d file at all, just text"[..]),
        Err(ReadError::C3d(C3dError::TooShort { len: 32 }))
    ));
}

/// Rewrites the two-character POINT:UNITS value of a file our writer produced.
fn with_units(bytes: &[u8], units: &[u8; 2]) -> Vec<u8> {
    let mut out = bytes.to_vec();
    let name = out
        .windows(5)
        .position(|w| w == b"UNITS")
        .expect("POINT:UNITS record");
    // name, offset word, type, dimension count, one dimension, then the characters.
    let data = name + 5 + 2 + 1 + 1 + 1;
    assert_eq!(&out[data..data + 2], b"mm");
    out[data..data + 2].copy_from_slice(units);
    out
}

#[test]
fn metres_and_centimetres_are_converted_to_millimetres() {
    let take = synthetic(3, 10, 1, 100.0);
    let bytes = write_bytes(&take);
    for (units, factor, expected) in [
        (b"cm", 10.0, replay::Units::Centimetres),
        (b"m ", 1000.0, replay::Units::Metres),
    ] {
        let back = c3d::read(&with_units(&bytes, units)[..]).expect("reads");
        assert_eq!(back.source_units, expected);
        assert_eq!(back.missing, take.missing);
        for (a, b) in take.positions.iter().zip(&back.positions) {
            assert!(
                (a * factor - b).abs() <= 1e-3 * b.abs().max(1.0),
                "{a} x {factor} vs {b}"
            );
        }
    }
    let err = c3d::read(&with_units(&bytes, b"ft")[..]).expect_err("feet are not supported");
    assert_eq!(
        err.to_string(),
        "unknown units \"ft\" (expected mm, cm or m)"
    );
}

/// Files the fuzzer found that made c3dio allocate without bound (see fixtures/SOURCE.md): the
/// reader returns, and where it reads the take it did so with our own decoder alone and says
/// why c3dio was not asked. Without the guards, c3dio allocates 3.8 GB for the first and loops
/// growing a vector until memory runs out on the second.
#[test]
fn files_that_make_c3dio_allocate_without_bound_never_reach_it() {
    let bytes = std::fs::read(fixture("fuzz/c3dio-analog-grid.c3d")).expect("fixture");
    let (_, info) = c3d::read_with_info(&bytes).expect("our decoder reads it");
    assert_eq!(info.decoder, Decoder::Fallback);
    let error = info.c3dio_error.unwrap_or_default();
    assert!(error.contains("analog samples"), "{error}");
    // This one is refused after the cross-check, for its values.
    let bytes = std::fs::read(fixture("fuzz/c3dio-walks-back.c3d")).expect("fixture");
    let err = c3d::read_with_info(&bytes).expect_err("its values are not positions");
    assert!(err.to_string().contains("not a position"), "{err}");
}
