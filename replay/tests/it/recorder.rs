//! The streaming recorder writes what `replay::save` writes, frame by frame.
#![allow(clippy::unwrap_used)] // a failed unwrap is a failed test

use std::path::Path;

use replay::c3d::C3dLimitError;
use replay::recorder::Recorder;
use replay::{Take, WriteError};

/// `frames` frames of three markers with gaps: marker 1 missing every 5th frame, marker 2 for a
/// run of frames, and values that need full f32 precision.
fn take_with_gaps(frames: usize, first_frame: i64) -> Take {
    let labels = vec!["Chin".into(), "Lip_Upper".into(), "Nose Tip".into()];
    let mut take = Take::new(labels, 120.0, first_frame);
    for f in 0..frames {
        let t = f as f32;
        let xyz = [
            10.0 + 0.1234567 * t,
            -20.5 - t,
            300.125,
            1.0e-3 * t,
            -0.5,
            1234.5679 + t,
            std::f32::consts::PI,
            t.sin() * 50.0,
            -t,
        ];
        let missing = [false, f % 5 == 3, (7..12).contains(&f)];
        take.push_frame(&xyz, &missing);
    }
    take
}

fn record(path: &Path, take: &Take) -> u64 {
    let mut rec =
        Recorder::create(path, take.labels.clone(), take.rate_hz, take.first_frame).unwrap();
    for f in 0..take.n_frames() {
        rec.push_frame(take.frame(f), take.frame_missing(f))
            .unwrap();
    }
    rec.finish().unwrap().frames
}

fn assert_same(recorded: &Take, saved: &Take) {
    assert_eq!(recorded.labels, saved.labels);
    assert_eq!(recorded.rate_hz, saved.rate_hz);
    assert_eq!(recorded.first_frame, saved.first_frame);
    assert_eq!(recorded.n_frames(), saved.n_frames());
    assert_eq!(recorded.missing, saved.missing, "same gaps");
    for (a, b) in recorded.positions.iter().zip(&saved.positions) {
        assert!((a - b).abs() <= 1e-3, "{a} vs {b}");
    }
}

/// For each format: record, save the same take, load both, compare.
#[test]
fn each_format_records_what_save_writes() {
    let dir = tempfile::tempdir().unwrap();
    let take = take_with_gaps(40, 7);
    for ext in ["c3d", "trc", "csv"] {
        let recorded_path = dir.path().join(format!("recorded.{ext}"));
        let saved_path = dir.path().join(format!("saved.{ext}"));
        assert_eq!(record(&recorded_path, &take), 40, "{ext}");
        replay::save(&saved_path, &take).unwrap();
        let recorded = replay::load(&recorded_path).unwrap();
        let saved = replay::load(&saved_path).unwrap();
        assert_same(&recorded, &saved);
        assert_same(&recorded, &take);
    }
}

/// C3D data and the CSV file are byte-identical to `save`; only C3D's reserved parameter room
/// and TRC's padded counts differ.
#[test]
fn c3d_frames_and_csv_are_byte_identical_to_save() {
    let dir = tempfile::tempdir().unwrap();
    let take = take_with_gaps(25, 1);
    let (rec, saved) = (dir.path().join("r.csv"), dir.path().join("s.csv"));
    record(&rec, &take);
    replay::save(&saved, &take).unwrap();
    assert_eq!(std::fs::read(&rec).unwrap(), std::fs::read(&saved).unwrap());

    let (rec, saved) = (dir.path().join("r.c3d"), dir.path().join("s.c3d"));
    record(&rec, &take);
    replay::save(&saved, &take).unwrap();
    let (r, s) = (std::fs::read(&rec).unwrap(), std::fs::read(&saved).unwrap());
    let data = |bytes: &[u8]| {
        let block = usize::from(u16::from_le_bytes([bytes[16], bytes[17]]));
        bytes[(block - 1) * 512..].to_vec()
    };
    assert_eq!(data(&r), data(&s));
    assert_eq!(r.len() % 512, 0, "whole blocks");
}

/// Past 65,535 frames C3D needs POINT:LONG_FRAMES and TRIAL's 32-bit range, patched on finish
/// into room reserved up front.
#[test]
fn a_long_c3d_recording_patches_long_frames() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("long.c3d");
    let labels = vec!["a".to_string()];
    let mut rec = Recorder::create(&path, labels, 1000.0, 1).unwrap();
    let n = 70_000;
    for f in 0..n {
        let v = f as f32;
        rec.push_frame(&[v, 1.0, 2.0], &[f == 123]).unwrap();
    }
    assert_eq!(rec.finish().unwrap().frames, n as u64);
    let take = replay::load(&path).unwrap();
    assert_eq!((take.n_frames(), take.first_frame), (n, 1));
    assert_eq!(take.sample(n - 1, 0), Some([(n - 1) as f32, 1.0, 2.0]));
    assert_eq!(take.sample(123, 0), None);
}

/// Zero frames: TRC and CSV are valid empty takes; C3D cannot hold one, so the file is removed
/// and the error says why.
#[test]
fn zero_frames_is_an_empty_take_or_a_clear_c3d_error() {
    let dir = tempfile::tempdir().unwrap();
    let labels = vec!["a".to_string(), "b".to_string()];
    for ext in ["trc", "csv"] {
        let path = dir.path().join(format!("empty.{ext}"));
        let rec = Recorder::create(&path, labels.clone(), 60.0, 1).unwrap();
        assert_eq!(rec.finish().unwrap().frames, 0);
        let take = replay::load(&path).unwrap();
        assert_eq!((take.n_frames(), take.labels.clone()), (0, labels.clone()));
        assert_eq!(take.rate_hz, 60.0);
    }
    let path = dir.path().join("empty.c3d");
    let rec = Recorder::create(&path, labels, 60.0, 1).unwrap();
    let err = rec.finish().unwrap_err();
    assert!(
        matches!(err, WriteError::C3dLimit(C3dLimitError::NoFrames)),
        "{err}"
    );
    assert!(!path.exists(), "no unreadable file is left behind");
}

/// Dropping a recorder without finish still leaves a complete file.
#[test]
fn a_dropped_recorder_leaves_a_readable_file() {
    let dir = tempfile::tempdir().unwrap();
    let take = take_with_gaps(12, 3);
    for ext in ["c3d", "trc", "csv"] {
        let path = dir.path().join(format!("dropped.{ext}"));
        {
            let mut rec =
                Recorder::create(&path, take.labels.clone(), take.rate_hz, take.first_frame)
                    .unwrap();
            for f in 0..take.n_frames() {
                rec.push_frame(take.frame(f), take.frame_missing(f))
                    .unwrap();
            }
        }
        assert_same(&replay::load(&path).unwrap(), &take);
    }
}

#[test]
fn bad_input_is_rejected_with_typed_errors() {
    let dir = tempfile::tempdir().unwrap();
    let labels = vec!["a".to_string(), "b".to_string()];
    let err = Recorder::create(&dir.path().join("x.txt"), labels.clone(), 60.0, 1).unwrap_err();
    assert!(matches!(err, WriteError::UnknownFormat(_)), "{err}");
    let err = Recorder::create(&dir.path().join("x.csv"), labels.clone(), 0.0, 1).unwrap_err();
    assert!(matches!(err, WriteError::Invalid(_)), "{err}");
    let bad_label = vec!["a,b".to_string()];
    let err = Recorder::create(&dir.path().join("x.csv"), bad_label, 60.0, 1).unwrap_err();
    assert!(
        matches!(err, WriteError::LabelUnrepresentable { .. }),
        "{err}"
    );
    let err = Recorder::create(&dir.path().join("x.c3d"), labels.clone(), 60.0, -1).unwrap_err();
    assert!(matches!(err, WriteError::C3dLimit(_)), "{err}");

    let path = dir.path().join("ok.trc");
    let mut rec = Recorder::create(&path, labels, 60.0, 1).unwrap();
    let err = rec.push_frame(&[1.0; 3], &[false]).unwrap_err();
    assert!(matches!(err, WriteError::Invalid(_)), "{err}");
    let err = rec
        .push_frame(&[1.0, f32::NAN, 1.0, 0.0, 0.0, 0.0], &[false, true])
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        "marker \"a\" at frame index 0 is not finite"
    );
    // A missing marker's NaN positions are fine, and the rejected frames left nothing behind.
    rec.push_frame(
        &[1.0, 2.0, 3.0, f32::NAN, f32::NAN, f32::NAN],
        &[false, true],
    )
    .unwrap();
    assert_eq!(rec.finish().unwrap().frames, 1);
    let take = replay::load(&path).unwrap();
    assert_eq!(take.n_frames(), 1);
    assert_eq!(take.sample(0, 1), None);
}

/// Issue 36: frames reach the file, and its header's count, while recording: read mid-take, as
/// a crash would leave it, the file holds every frame pushed more than a sync ago.
#[test]
fn frames_reach_the_file_and_its_count_as_they_are_pushed() {
    let dir = tempfile::tempdir().unwrap();
    for ext in ["c3d", "trc", "csv"] {
        let path = dir.path().join(format!("stream.{ext}"));
        let labels: Vec<String> = (0..40).map(|i| format!("m{i}")).collect();
        let mut rec = Recorder::create(&path, labels, 120.0, 1).unwrap();
        let xyz: Vec<f32> = (0..120).map(|v| v as f32 * 1.25).collect();
        let missing = [false; 40];
        for round in 1..=2 {
            for _ in 0..300 {
                rec.push_frame(&xyz, &missing).unwrap();
            }
            std::thread::sleep(replay::recorder::SYNC + replay::recorder::SYNC / 2);
            let mid = replay::load(&path).unwrap();
            assert_eq!(mid.n_frames(), 300 * round, "{ext} before finish");
        }
        assert_eq!(rec.frames(), 600);
        rec.finish().unwrap();
        assert_eq!(replay::load(&path).unwrap().n_frames(), 600);
    }
}

/// Issue 16: a live recording keeps its timecode: a CSV column per frame, the first frame's in
/// TRC's header and C3D's TIMECODE group (drop-frame included), the measured rate as TRC's
/// CameraRate and C3D's TRIAL:CAMERA_RATE; all three still read back as takes.
#[test]
fn timecode_and_measured_rate_go_into_every_format() {
    use protocol::{Smpte, TimecodeRate};
    use replay::recorder::RecordTime;
    let dir = tempfile::tempdir().unwrap();
    let labels = vec!["Chin".to_string(), "Nose".to_string()];
    let rate = TimecodeRate::DF_29_97;
    // 120 Hz capture on 29.97 DF timecode: 4 subframes a timecode frame, across a minute.
    let first = Smpte::from_frame_count(1_799, rate);
    let stamp = |k: u32| {
        let mut t = Smpte::from_frame_count(1_799 + u64::from(k / 4), rate);
        t.subframe = k % 4;
        t
    };
    for ext in ["csv", "trc", "c3d"] {
        let path = dir.path().join(format!("live.{ext}"));
        let time = RecordTime {
            timecode: Some(first),
            camera_rate_hz: None,
        };
        let mut rec = Recorder::create_timed(&path, labels.clone(), 120.0, 1, time).unwrap();
        for k in 0..8u32 {
            let xyz = [1.0, 2.0, k as f32, 4.0, 5.0, 6.0];
            rec.push_frame_timed(&xyz, &[false, k == 3], Some(&stamp(k)))
                .unwrap();
        }
        rec.set_camera_rate(119.88);
        rec.finish().unwrap();
        let take = replay::load(&path).unwrap();
        assert_eq!((take.n_frames(), take.sample(3, 1)), (8, None), "{ext}");
        let text = std::fs::read(&path).unwrap();
        match ext {
            "csv" => {
                let text = String::from_utf8(text).unwrap();
                let rows: Vec<&str> = text.lines().skip(2).collect();
                assert!(text
                    .lines()
                    .nth(1)
                    .unwrap()
                    .starts_with("frame,time,timecode,"));
                assert_eq!(rows[0].split(',').nth(2), Some("00:00:59;29.0"));
                assert_eq!(
                    rows[4].split(',').nth(2),
                    Some("00:01:00;02.0"),
                    "DF skips ;00 ;01"
                );
                assert_eq!(rows[7].split(',').nth(2), Some("00:01:00;02.3"));
            }
            "trc" => {
                let text = String::from_utf8(text).unwrap();
                let keys: Vec<&str> = text.lines().nth(1).unwrap().split('\t').collect();
                let values: Vec<&str> = text.lines().nth(2).unwrap().split('\t').collect();
                let at = |k: &str| values[keys.iter().position(|x| *x == k).unwrap()].trim();
                assert_eq!(at("Timecode"), "00:00:59;29.0");
                assert_eq!(at("CameraRate"), "119.880000");
                assert_eq!(at("DataRate"), "120");
            }
            _ => {
                let back = replay::c3d::read_time(&text).unwrap();
                assert_eq!(back.timecode, Some(first));
                assert!((back.camera_rate_hz.unwrap() - 119.88).abs() < 1e-3);
            }
        }
    }
}
