//! Issue 36: takes cut off by a crash read as the frames their header counts, `inspect` tells
//! what more they hold, and `repair` recovers every whole frame: on files the old recorder
//! left when killed, and on every state the new one can leave (header behind the data, a frame
//! or row cut at any byte).
#![allow(clippy::unwrap_used)] // a failed unwrap is a failed test

use std::path::{Path, PathBuf};

use replay::repair::{self, RepairError};
use replay::{Format, Take};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

/// The take the fixtures' generator recorded (see `tests/fixtures/SOURCE.md`), `frames` long.
fn generated(frames: usize) -> Take {
    let labels = (0..20).map(|m| format!("M{m:02}")).collect();
    let mut take = Take::new(labels, 120.0, 1);
    for f in 0..frames {
        let t = f as f32 / 120.0;
        let xyz: Vec<f32> = (0..20)
            .flat_map(|m| {
                let m = m as f32;
                [
                    100.0 * m + 12.5 * (t * 1.3 + m).sin(),
                    -250.5 + 30.0 * (t * 0.7).cos(),
                    1500.0 + t,
                ]
            })
            .collect();
        let missing: Vec<bool> = (0..20).map(|m| (f * 7 + m * 3) % 11 == 0).collect();
        take.push_frame(&xyz, &missing);
    }
    take
}

/// Samples equal to the text formats' precision (the shortest round-trip decimal: exact).
fn assert_same_frames(got: &Take, want: &Take, what: &str) {
    assert_eq!(got.n_frames(), want.n_frames(), "{what}: frames");
    assert_eq!(got.labels, want.labels, "{what}: labels");
    assert_eq!(got.first_frame, want.first_frame, "{what}: first frame");
    for f in 0..want.n_frames() {
        for m in 0..want.n_markers() {
            assert_eq!(
                got.sample(f, m),
                want.sample(f, m),
                "{what}: frame {f} marker {m}"
            );
        }
    }
}

#[test]
fn issue_36_repair_recovers_takes_killed_under_the_old_recorder() {
    let dir = tempfile::tempdir().expect("dir");
    for (name, header_said) in [
        ("killed-before-issue-36.c3d", 1),
        ("killed-before-issue-36.trc", 0),
    ] {
        let path = dir.path().join(name);
        std::fs::copy(fixture(name), &path).expect("fixture present");
        let before = repair::inspect(&path).expect("inspected");
        assert_eq!(before.header_frames, Some(header_said), "{name}");
        assert!(before.data_frames > 100, "{name}: {before:?}");
        let problem = before.problem().expect("damage found");
        assert_eq!(
            problem,
            format!(
                "holds {} frames, header says {header_said}",
                before.data_frames
            )
        );
        let out = dir.path().join(format!("repaired-{name}"));
        let repaired = repair::repair(&path, Some(&out)).expect("repaired");
        assert_eq!(repaired.frames, before.data_frames);
        assert_eq!(repaired.written.as_deref(), Some(out.as_path()));
        // The input is untouched; the output holds every frame the generator wrote.
        assert_eq!(
            std::fs::read(&path).unwrap(),
            std::fs::read(fixture(name)).unwrap()
        );
        let take = replay::load(&out).expect("reads after repair");
        assert_same_frames(&take, &generated(before.data_frames), name);
        assert_eq!(repair::inspect(&out).unwrap().problem(), None, "{name}");
        // In place too.
        let again = repair::repair(&path, None).expect("repaired in place");
        assert_eq!(again.written.as_deref(), Some(path.as_path()));
        assert_eq!(std::fs::read(&path).unwrap(), std::fs::read(&out).unwrap());
        // A second repair finds nothing to do and writes nothing.
        let none = repair::repair(&path, None).expect("nothing to do");
        assert_eq!((none.written, none.frames), (None, before.data_frames));
    }
}

/// The bytes of `take` written as `format` with its header counting `header_frames` and its
/// data holding `data_frames` whole frames then `torn` bytes of the next one: every state the
/// recorder can leave when killed between two header updates, or mid-write.
fn cut_off(
    format: Format,
    take: &Take,
    header_frames: usize,
    data_frames: usize,
    torn: usize,
) -> Vec<u8> {
    let head_of = |n: usize| {
        let mut short = take.clone();
        short.positions.truncate(n * take.n_markers() * 3);
        short.missing.truncate(n * take.n_markers());
        let mut bytes = Vec::new();
        replay::write_as(format, &short, &mut bytes).expect("writable");
        bytes
    };
    let full = head_of(take.n_frames());
    match format {
        Format::C3d => {
            let frame = take.n_markers() * 16;
            // The header's data block (word 9) says where the first frame starts.
            let head_len = (usize::from(u16::from_le_bytes([full[16], full[17]])) - 1) * 512;
            let mut bytes = head_of(header_frames)[..head_len].to_vec();
            bytes.extend_from_slice(&full[head_len..head_len + data_frames * frame + torn]);
            bytes
        }
        Format::Trc | Format::Csv => {
            let text = String::from_utf8(full).expect("utf-8");
            let header_lines = if format == Format::Trc { 6 } else { 2 };
            let lines: Vec<&str> = text.split_inclusive('\n').collect();
            let mut out = String::new();
            if format == Format::Trc {
                let counted = String::from_utf8(head_of(header_frames.max(1))).expect("utf-8");
                let counted: Vec<&str> = counted.split_inclusive('\n').collect();
                let values = counted[2].replacen(
                    &format!("\t{}\t", header_frames.max(1)),
                    &format!("\t{header_frames}\t"),
                    1,
                );
                let values = values.replace(
                    &format!("\t{}\n", header_frames.max(1)),
                    &format!("\t{header_frames}\n"),
                );
                out.push_str(lines[0]);
                out.push_str(lines[1]);
                out.push_str(&values);
                lines[3..header_lines].iter().for_each(|l| out.push_str(l));
            } else {
                lines[..header_lines].iter().for_each(|l| out.push_str(l));
            }
            let rows = &lines[header_lines..];
            rows[..data_frames].iter().for_each(|l| out.push_str(l));
            if let Some(next) = rows.get(data_frames) {
                out.push_str(&next[..torn]);
            }
            out.into_bytes()
        }
    }
}

fn read(format: Format, bytes: &[u8]) -> Result<Take, replay::ReadError> {
    match format {
        Format::C3d => replay::c3d::read(bytes),
        Format::Trc => replay::trc::read(bytes),
        Format::Csv => replay::csv::read(bytes),
    }
}

fn first(take: &Take, frames: usize) -> Take {
    let mut short = take.clone();
    short.positions.truncate(frames * take.n_markers() * 3);
    short.missing.truncate(frames * take.n_markers());
    short
}

#[test]
fn issue_36_a_take_cut_anywhere_reads_as_its_header_and_repairs_to_every_whole_frame() {
    let take = generated(12);
    let dir = tempfile::tempdir().expect("dir");
    for format in [Format::C3d, Format::Trc, Format::Csv] {
        let row_len = {
            let bytes = cut_off(format, &take, 11, 11, 0);
            let with = cut_off(format, &take, 11, 12, 0);
            with.len() - bytes.len()
        };
        // Every byte of the last frame, the header behind (C3D, TRC) by a few frames.
        for torn in 0..row_len {
            let header_frames = if format == Format::Csv { 11 } else { 8 };
            let bytes = cut_off(format, &take, header_frames, 11, torn);
            let what = format!("{format:?} torn after {torn} bytes");
            let read_now = read(format, &bytes).unwrap_or_else(|e| panic!("{what}: {e}"));
            assert_same_frames(&read_now, &first(&take, header_frames), &what);
            // Repairs sync the disk: every cut is read, a spread of them repaired.
            if torn % 17 != 0 && torn > 3 && torn + 4 < row_len {
                continue;
            }
            let path = dir.path().join(format!("cut.{}", format.extension()));
            std::fs::write(&path, &bytes).unwrap();
            let extent = repair::inspect(&path).unwrap();
            assert_eq!(extent.data_frames, 11, "{what}");
            // A C3D tail of zero bytes is padding, not a torn frame.
            let tail = &bytes[bytes.len() - torn..];
            let zero = format == Format::C3d && tail.iter().all(|&b| b == 0);
            let torn_seen = if zero { 0 } else { torn as u64 };
            assert_eq!(extent.torn_bytes, torn_seen, "{what}");
            let repaired = repair::repair(&path, None).unwrap_or_else(|e| panic!("{what}: {e}"));
            assert_eq!(repaired.frames, 11, "{what}");
            let back = replay::load(&path).unwrap();
            assert_same_frames(&back, &first(&take, 11), &what);
        }
    }
}

/// A take recorded from a live source whose frame numbers passed 65535 (its header numbered
/// from 1, TRIAL holding the true range) repairs with its numbers kept.
#[test]
fn a_c3d_numbered_past_65535_repairs_with_its_numbers() {
    let mut take = generated(12);
    take.first_frame = 200_000;
    let dir = tempfile::tempdir().expect("dir");
    let path = dir.path().join("late.c3d");
    std::fs::write(&path, cut_off(Format::C3d, &take, 8, 11, 0)).unwrap();
    assert_same_frames(
        &replay::load(&path).unwrap(),
        &first(&take, 8),
        "before repair",
    );
    assert_eq!(repair::inspect(&path).unwrap().data_frames, 11);
    assert_eq!(repair::repair(&path, None).unwrap().frames, 11);
    assert_same_frames(&replay::load(&path).unwrap(), &first(&take, 11), "repaired");
}

#[test]
fn a_trc_last_row_without_its_newline_is_kept_when_the_header_counts_it() {
    // A file of another program that lacks its final newline is not damaged.
    let take = generated(3);
    let mut bytes = Vec::new();
    replay::write_as(Format::Trc, &take, &mut bytes).unwrap();
    assert_eq!(bytes.pop(), Some(b'\n'));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("no-final-newline.trc");
    std::fs::write(&path, &bytes).unwrap();
    let extent = repair::inspect(&path).unwrap();
    assert_eq!((extent.data_frames, extent.problem()), (3, None));
    assert_eq!(replay::load(&path).unwrap().n_frames(), 3);
}

#[test]
fn nothing_to_keep_is_a_clear_error() {
    let take = generated(2);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("none.c3d");
    std::fs::write(&path, cut_off(Format::C3d, &take, 1, 0, 100)).unwrap();
    let e = repair::repair(&path, None).unwrap_err();
    assert!(matches!(e, RepairError::NoFrames), "{e}");
    assert_eq!(
        e.to_string(),
        "no whole frame to keep: a take needs at least one"
    );
}
