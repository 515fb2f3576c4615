use std::net::SocketAddr;

use super::*;

#[test]
fn later_streams_get_numbered_files_beside_the_first() {
    let p = Path::new("/tmp/take.c3d");
    assert_eq!(stream_path(p, 1), PathBuf::from("/tmp/take.c3d"));
    assert_eq!(stream_path(p, 3), PathBuf::from("/tmp/take.3.c3d"));
    assert_eq!(
        stream_path(Path::new("out/a.v1.trc"), 2),
        PathBuf::from("out/a.v1.2.trc")
    );
}

#[test]
fn bad_paths_are_refused_at_start() {
    let dir = tempfile::tempdir().expect("temp dir");
    let ok = dir.path().join("a.csv");
    assert!(matches!(
        Recording::start(&dir.path().join("a.txt"), None, false),
        Err(RecordError::Extension { .. })
    ));
    assert!(matches!(
        Recording::start(&ok, Some(&ok), false),
        Err(RecordError::SamePath { .. })
    ));
    assert!(matches!(
        Recording::start(&ok, Some(&dir.path().join("missing/raw.c3d")), false),
        Err(RecordError::Io { .. })
    ));
    assert!(Recording::start(&ok, Some(&dir.path().join("raw.trc")), false).is_ok());
}

fn emitted<'a>(
    key: StreamKey,
    n: i32,
    labels: &'a [String],
    xyz: &'a [f32],
    input: &'a protocol::FrameBuf,
) -> RecordFrame<'a> {
    RecordFrame {
        key,
        labels,
        input_labels: labels,
        rate_hz: 60.0,
        frame_number: n,
        frames_since_last: 1,
        timecode: None,
        xyz,
        input,
    }
}

#[test]
fn two_performers_are_recorded_to_their_own_files_never_mixed() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (edited, raw) = (dir.path().join("take.csv"), dir.path().join("in.csv"));
    let mut rec = Recording::start(&edited, Some(&raw), false).expect("paths are fine");
    let labels: Vec<String> = vec!["a".into(), "b".into()];
    let key = |port| StreamKey {
        source: SocketAddr::from(([127, 0, 0, 1], port)),
        layout_id: 0,
    };
    let mut input = protocol::FrameBuf::with_max_markers(2);
    for n in 0..5 {
        for (k, port) in [(1.0, 7000), (2.0, 7001)] {
            let xyz = [k, 0.0, 0.0, k, 1.0, 0.0];
            input.set_frame(n, 0, &xyz).expect("finite");
            input.set_missing(1, n == 2);
            rec.push(&emitted(key(port), n, &labels, &xyz, &input));
        }
    }
    assert_eq!(rec.finish().expect("closes"), 10);
    for (path, k, gaps) in [
        (edited.clone(), 1.0, false),
        (stream_path(&edited, 2), 2.0, false),
        (raw.clone(), 1.0, true),
        (stream_path(&raw, 2), 2.0, true),
    ] {
        let take = replay::load(&path).expect("loads");
        assert_eq!(take.n_frames(), 5, "{}", path.display());
        assert!(take.frame(4)[..3] == [k, 0.0, 0.0], "{}", path.display());
        assert_eq!(take.is_missing(2, 1), gaps, "{}", path.display());
    }
}

fn key(port: u16) -> StreamKey {
    StreamKey {
        source: SocketAddr::from(([127, 0, 0, 1], port)),
        layout_id: 0,
    }
}

#[test]
fn numbered_names_never_collide_with_the_paths_given() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (edited, raw) = (dir.path().join("take.csv"), dir.path().join("take.2.csv"));
    let mut rec = Recording::start(&edited, Some(&raw), false).expect("paths are fine");
    let labels: Vec<String> = vec!["a".into()];
    let mut input = protocol::FrameBuf::with_max_markers(1);
    for (k, port) in [(1.0, 7000), (2.0, 7001)] {
        let xyz = [k, 0.0, 0.0];
        input.set_frame(0, 0, &xyz).expect("finite");
        rec.push(&emitted(key(port), 0, &labels, &xyz, &input));
    }
    rec.finish().expect("closes");
    // stream 2's edited file skips take.2.csv, which is stream 1's raw file
    for (name, k) in [
        ("take.csv", 1.0),
        ("take.2.csv", 1.0),
        ("take.3.csv", 2.0),
        ("take.2.2.csv", 2.0),
    ] {
        let take = replay::load(&dir.path().join(name)).expect(name);
        assert_eq!(take.frame(0)[0], k, "{name}");
    }
}

#[test]
fn lost_frames_become_gaps_and_new_labels_a_new_file() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("take.csv");
    let mut rec = Recording::start(&path, None, false).expect("path is fine");
    let (one, two): (Vec<String>, Vec<String>) = (vec!["a".into()], vec!["b".into()]);
    let input = protocol::FrameBuf::with_max_markers(1);
    for (n, since) in [(0, 1), (1, 1), (4, 3)] {
        let mut e = emitted(key(7000), n, &one, &[1.0, 2.0, 3.0], &input);
        e.frames_since_last = since;
        rec.push(&e);
    }
    rec.push(&emitted(key(7000), 5, &two, &[4.0, 5.0, 6.0], &input));
    rec.finish().expect("closes");
    let take = replay::load(&path).expect("loads");
    assert_eq!(take.n_frames(), 5, "frames 0..=4, two of them lost");
    let gaps: Vec<bool> = (0..5).map(|f| take.is_missing(f, 0)).collect();
    assert_eq!(gaps, [false, false, true, true, false]);
    let relabelled = replay::load(&stream_path(&path, 2)).expect("a second file");
    assert_eq!(relabelled.labels, two);
    assert_eq!(relabelled.first_frame, 5);
}

#[test]
fn a_refused_start_truncates_nothing() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("take.csv");
    std::fs::write(&path, "keep me").expect("write");
    let bad_raw = dir.path().join("missing/raw.csv");
    // Even when overwriting is allowed, a start refused for another reason touches nothing.
    assert!(Recording::start(&path, Some(&bad_raw), true).is_err());
    assert!(Recording::start(&path, Some(&dir.path().join("raw.txt")), true).is_err());
    assert!(Recording::start(&path, Some(&dir.path().join("./take.csv")), true).is_err());
    assert!(matches!(
        Recording::start(&path, None, false),
        Err(RecordError::Exists { .. })
    ));
    assert_eq!(std::fs::read_to_string(&path).expect("read"), "keep me");
}
