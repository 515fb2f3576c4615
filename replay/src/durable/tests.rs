//! The file's thread against a fake disk: counts follow the synced data, a write error keeps
//! the whole frames, a disk far behind stops the file (or makes the caller wait).

use std::fs::File;
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::Path;
use std::sync::{Arc, Mutex};

use super::*;

/// A header of 8 bytes holding the count, frames of `frame_bytes`; every count recorded.
struct Counter {
    counts: Arc<Mutex<Vec<u64>>>,
    frame_bytes: usize,
}

impl Header for Counter {
    fn count(&mut self, file: &mut File, frames: u64, _: Option<f64>) -> std::io::Result<()> {
        self.counts.lock().expect("lock").push(frames);
        file.seek(SeekFrom::Start(0))?;
        file.write_all(&frames.to_le_bytes())
    }

    fn whole(&self, bytes: &[u8]) -> (u64, usize) {
        let n = bytes.len() / self.frame_bytes;
        (n as u64, n * self.frame_bytes)
    }

    fn close(&mut self, _: &mut File, _: &Path, _: u64) -> std::io::Result<()> {
        Ok(())
    }
}

fn start(path: &Path, behind: Behind, frame_bytes: usize) -> (DurableFile, Arc<Mutex<Vec<u64>>>) {
    let mut file = File::create(path).expect("created");
    file.write_all(&[0; 8]).expect("header");
    let counts = Arc::new(Mutex::new(Vec::new()));
    let header = Box::new(Counter {
        counts: Arc::clone(&counts),
        frame_bytes,
    });
    (
        DurableFile::start(file, path, header, behind).expect("thread"),
        counts,
    )
}

/// The count in the header, and the bytes of data after it.
fn on_disk(path: &Path) -> (u64, usize) {
    let mut bytes = Vec::new();
    File::open(path)
        .and_then(|mut f| f.read_to_end(&mut bytes))
        .expect("read");
    let count = u64::from_le_bytes(bytes[..8].try_into().expect("8 bytes"));
    (count, bytes.len() - 8)
}

#[test]
fn the_header_counts_the_frames_on_disk_within_a_sync_and_finish_counts_all() {
    let dir = tempfile::tempdir().expect("dir");
    let path = dir.path().join("take");
    let (file, counts) = start(&path, Behind::Stop, 4);
    for f in 0u32..10 {
        file.append(&f.to_le_bytes()).expect("appended");
    }
    // One sync period is enough on an idle host; a loaded one (a CI build on both cores, a
    // disk busy with another job's writeback) may take a few: wait for it, within bounds.
    let deadline = std::time::Instant::now() + 10 * (SYNC + FLUSH);
    std::thread::sleep(SYNC + FLUSH);
    while on_disk(&path) != (10, 40) && std::time::Instant::now() < deadline {
        std::thread::sleep(FLUSH);
    }
    assert_eq!(on_disk(&path), (10, 40), "counted without a finish");
    file.append(&10u32.to_le_bytes()).expect("appended");
    assert_eq!(file.finish().expect("closed"), 11);
    assert_eq!(on_disk(&path), (11, 44));
    let counts = counts.lock().expect("lock");
    assert!(counts.windows(2).all(|w| w[0] <= w[1]), "{counts:?}");
}

#[test]
fn a_disk_far_behind_stops_a_live_file_and_keeps_what_it_wrote() {
    let dir = tempfile::tempdir().expect("dir");
    let path = dir.path().join("take");
    let (file, _) = start(&path, Behind::Stop, MAX_PENDING / 2);
    let frame = vec![7u8; MAX_PENDING / 2];
    // Two halves fit; a third cannot arrive before the thread takes them (it waits FLUSH).
    let mut refused = None;
    for _ in 0..64 {
        if let Err(e) = file.append(&frame) {
            refused = Some(e);
            break;
        }
    }
    let e = refused.expect("refused once the disk is behind");
    assert!(
        e.cause.to_string().contains("did not keep up"),
        "{}",
        e.cause
    );
    let later = file
        .append(&[1, 2, 3, 4])
        .expect_err("refused from then on");
    assert!(later.cause.to_string().contains("did not keep up"));
    let end = file.finish().expect_err("reports the stop");
    let (count, bytes) = on_disk(&path);
    assert_eq!(count, end.frames);
    assert_eq!(bytes, end.frames as usize * frame.len());
}

#[test]
fn a_write_error_stops_the_file_with_its_cause() {
    // /dev/full refuses every write with ENOSPC, as a full disk does.
    let file = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .expect("/dev/full, as on every Linux");
    let header = Box::new(Counter {
        counts: Arc::default(),
        frame_bytes: 4,
    });
    let dir = tempfile::tempdir().expect("dir");
    let out =
        DurableFile::start(file, &dir.path().join("full"), header, Behind::Stop).expect("thread");
    out.append(&[1, 2, 3, 4]).expect("nothing written yet");
    let e = out.finish().expect_err("the disk is full");
    assert_eq!(e.frames, 0);
    assert!(
        e.cause.to_string().starts_with("No space left on device"),
        "{}",
        e.cause
    );
}

#[test]
fn an_offline_file_waits_for_the_disk_instead() {
    let dir = tempfile::tempdir().expect("dir");
    let path = dir.path().join("take");
    let (file, _) = start(&path, Behind::Wait, MAX_PENDING / 4);
    let frame = vec![7u8; MAX_PENDING / 4];
    for _ in 0..8 {
        file.append(&frame).expect("waits, never refuses");
    }
    let frames = file.finish().expect("closed");
    assert_eq!(frames, 8);
    assert_eq!(on_disk(&path), (8, 2 * MAX_PENDING));
}
