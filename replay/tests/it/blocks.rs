//! Issue 18: takes read and written in blocks of frames give what the whole-file reader and
//! writer give, for every format, block size and damaged file.

use std::path::{Path, PathBuf};

use replay::blocks::BlockReader;
use replay::c3d::C3dError;
use replay::TakeWriter;
use replay::{Format, ReadError, Take};

const FORMATS: [Format; 3] = [Format::C3d, Format::Trc, Format::Csv];

/// A take with motion and missing samples (whole-frame gaps and a marker missing at the ends).
fn synthetic(markers: usize, frames: usize, first_frame: i64) -> Take {
    let labels = (0..markers).map(|m| format!("marker_{m:02}")).collect();
    let mut take = Take::new(labels, 120.0, first_frame);
    for f in 0..frames {
        let t = f as f32 / 120.0;
        let xyz: Vec<f32> = (0..markers)
            .flat_map(|m| {
                let m = m as f32;
                [
                    100.0 * m + 12.345 * (t * 1.3 + m).sin(),
                    -250.5 + 30.0 * (t * 0.7).cos(),
                    1500.125 + 0.001 * f as f32,
                ]
            })
            .collect();
        let gone: Vec<bool> = (0..markers)
            .map(|m| (f * 7 + m * 3) % 11 == 0 || (m == 1 && (f == 0 || f + 1 == frames)))
            .collect();
        take.push_frame(&xyz, &gone);
    }
    take
}

fn bytes_of(format: Format, take: &Take) -> Vec<u8> {
    let mut out = Vec::new();
    replay::write_as(format, take, &mut out).expect("a writable take");
    out
}

fn whole(format: Format, bytes: &[u8]) -> Result<Take, ReadError> {
    match format {
        Format::C3d => replay::c3d::read(bytes),
        Format::Trc => replay::trc::read(bytes),
        Format::Csv => replay::csv::read(bytes),
    }
}

/// The take read in blocks of `size`, every block checked to start where the last ended.
fn in_blocks(format: Format, bytes: &[u8], size: usize) -> Result<Take, ReadError> {
    let mut reader = BlockReader::new(format, bytes, Some(bytes.len() as u64))?;
    let mut take = reader.header().empty_take();
    let mut block = reader.header().empty_take();
    loop {
        let n = reader.read_block(size, &mut block)?;
        if n == 0 {
            break;
        }
        assert!(n <= size, "a block of {n} frames for a size of {size}");
        assert_eq!(block.first_frame, take.first_frame + take.n_frames() as i64);
        take.positions.extend_from_slice(&block.positions);
        take.missing.extend_from_slice(&block.missing);
    }
    take.rate_hz = reader.rate_hz()?;
    Ok(take)
}

#[test]
fn blocks_of_any_size_read_what_the_whole_file_reader_reads() {
    let take = synthetic(5, 30, 7);
    assert!(take.missing.iter().any(|&m| m), "the take has gaps");
    for format in FORMATS {
        let bytes = bytes_of(format, &take);
        let expected = whole(format, &bytes).expect("whole read");
        for size in [1, 7, 1000] {
            let got = in_blocks(format, &bytes, size).expect("block read");
            assert_eq!(got, expected, "{format:?} in blocks of {size}");
        }
    }
}

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

#[test]
fn recorded_c3d_files_read_the_same_in_blocks() {
    // Intel int16, MIPS and DEC float layouts, analog samples between frames.
    for name in ["Eb015pi.c3d", "Eb015sr.c3d", "Eb015vr.c3d", "TESTBPI.c3d"] {
        let bytes = std::fs::read(fixture(name)).expect("fixture present");
        let expected = whole(Format::C3d, &bytes).expect("whole read");
        let got = in_blocks(Format::C3d, &bytes, 7).expect("block read");
        assert_eq!(got, expected, "{name}");
    }
    let trc = std::fs::read(fixture("NoseMoCap_first60.trc")).expect("fixture present");
    let expected = whole(Format::Trc, &trc).expect("whole read");
    assert_eq!(in_blocks(Format::Trc, &trc, 7).expect("blocks"), expected);
}

#[test]
fn truncated_files_are_errors_in_blocks_too() {
    let take = synthetic(5, 30, 1);
    for format in FORMATS {
        let bytes = bytes_of(format, &take);
        // Cut inside the data: mid-frame for C3D, a few cells into a row for the text formats.
        let at = match format {
            Format::C3d => bytes.len() - 700,
            _ => {
                bytes.len() / 2
                    + bytes[bytes.len() / 2..]
                        .iter()
                        .position(|&b| b == b'\n')
                        .expect("rows")
                    + 30
            }
        };
        let cut = &bytes[..at];
        if format == Format::Csv {
            // CSV has no count: a row cut off mid-write ends the take cleanly (issue 36).
            let rows = whole(format, cut).expect("the rows before the cut");
            assert!(rows.n_frames() > 0 && rows.n_frames() < take.n_frames());
            for size in [1, 7, 1000] {
                assert_eq!(in_blocks(format, cut, size).expect("blocks"), rows);
            }
            continue;
        }
        let expected = whole(format, cut).expect_err("a truncated file");
        for size in [1, 7, 1000] {
            let e = in_blocks(format, cut, size).expect_err("a truncated file");
            let typed = matches!(
                (format, &e),
                (Format::C3d, ReadError::C3d(C3dError::Truncated { .. }))
                    | (Format::Trc, ReadError::TruncatedRow { .. })
            );
            assert!(typed, "{format:?}: {e}");
            assert_eq!(e.to_string(), expected.to_string(), "{format:?}");
        }
    }
    // A C3D file whose length is not known up front fails at the frame that is cut.
    let bytes = bytes_of(Format::C3d, &take);
    let cut = &bytes[..bytes.len() - 700];
    let mut reader = BlockReader::new(Format::C3d, cut, None).expect("header intact");
    let mut block = reader.header().empty_take();
    let e = loop {
        match reader.read_block(4, &mut block) {
            Ok(0) => panic!("a cut file read to its end"),
            Ok(_) => {}
            Err(e) => break e,
        }
    };
    assert!(
        matches!(e, ReadError::C3d(C3dError::Truncated { .. })),
        "{e}"
    );
}

/// Writes `take` through a [`TakeWriter`] in blocks of `size` and returns the file's bytes.
fn written_in_blocks(format: Format, take: &Take, size: usize, count: Option<usize>) -> Vec<u8> {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join(format!("out.{}", format.extension()));
    let at = (take.rate_hz, take.first_frame);
    let mut writer = TakeWriter::create(&path, &take.labels, at, count).expect("header");
    let mut block = Take::new(take.labels.clone(), take.rate_hz, take.first_frame);
    for start in (0..take.n_frames()).step_by(size) {
        block.positions.clear();
        block.missing.clear();
        for f in start..(start + size).min(take.n_frames()) {
            block.push_frame(take.frame(f), take.frame_missing(f));
        }
        writer.write_block(&block).expect("block written");
    }
    assert_eq!(writer.frames(), take.n_frames());
    writer.finish().expect("file complete");
    std::fs::read(&path).expect("written")
}

#[test]
fn blocks_written_with_a_known_count_are_the_whole_file_byte_for_byte() {
    let take = synthetic(5, 30, 3);
    for format in FORMATS {
        let expected = bytes_of(format, &take);
        for size in [1, 7, 1000] {
            let got = written_in_blocks(format, &take, size, Some(take.n_frames()));
            assert!(got == expected, "{format:?} in blocks of {size}");
        }
        // Without a count the header is patched at the end; the take is the same.
        let got = written_in_blocks(format, &take, 7, None);
        assert_eq!(whole(format, &got).expect("readable"), take, "{format:?}");
    }
}

#[test]
fn a_writer_refuses_another_count_than_it_declared() {
    let take = synthetic(3, 10, 1);
    let dir = tempfile::tempdir().expect("temp dir");
    for format in [Format::C3d, Format::Trc] {
        let path = dir.path().join(format!("short.{}", format.extension()));
        let at = (take.rate_hz, take.first_frame);
        let mut writer = TakeWriter::create(&path, &take.labels, at, Some(11)).expect("header");
        writer.write_block(&take).expect("10 of 11 frames");
        let e = writer.finish().expect_err("a frame short");
        assert!(e.to_string().contains("declares 11 frames"), "{e}");
        let mut writer = TakeWriter::create(&path, &take.labels, at, Some(9)).expect("header");
        assert!(
            writer.write_block(&take).is_err(),
            "{format:?}: one too many"
        );
    }
}

#[test]
fn damaged_c3d_is_an_error_in_blocks_never_a_panic() {
    let bytes = bytes_of(Format::C3d, &synthetic(4, 20, 1));
    let read_all = |data: &[u8], len: Option<u64>| -> Result<usize, ReadError> {
        let mut reader = BlockReader::new(Format::C3d, data, len)?;
        let mut block = reader.header().empty_take();
        let mut frames = 0;
        while let n @ 1.. = reader.read_block(3, &mut block)? {
            frames += n;
        }
        Ok(frames)
    };
    assert_eq!(read_all(&bytes, None).expect("intact"), 20);
    // The last block is padding after the data: any cut before it loses frames.
    for cut in (0..bytes.len() - 512).step_by(37) {
        assert!(read_all(&bytes[..cut], None).is_err(), "cut at {cut}");
    }
    // Every header and parameter byte set to a few bad values: an error or a take, no panic.
    let end = 2 * 512 + 512;
    for at in 0..end.min(bytes.len()) {
        for value in [0u8, 1, 0x7f, 0xff] {
            let mut damaged = bytes.clone();
            damaged[at] = value;
            let _ = read_all(&damaged, Some(damaged.len() as u64));
        }
    }
}
