use super::*;
use engine::{StreamKey, StreamStatus};

fn status(id: i32, unmatched: usize) -> StreamStatus {
    StreamStatus {
        key: StreamKey {
            source: "127.0.0.1:9000".parse().expect("addr"),
            layout_id: id,
        },
        id,
        name: format!("s{id}"),
        performer: None,
        model_markers: 109,
        unmatched_markers: unmatched,
        target: String::new(),
        amount: 0.0,
        frames: 1,
        duplicates: 0,
        stale: 0,
    }
}

/// Each stream is announced once while it lives, and again if it comes back after going.
#[test]
fn streams_are_announced_once_while_they_live() {
    let mut announced = Vec::new();
    announce_streams(&mut announced, &[status(0, 0), status(1, 69)]);
    assert_eq!(announced, [0, 1]);
    announce_streams(&mut announced, &[status(0, 0), status(1, 69)]);
    assert_eq!(announced, [0, 1]);
    announce_streams(&mut announced, &[status(1, 69)]);
    assert_eq!(announced, [1], "a stream gone is forgotten");
    announce_streams(&mut announced, &[status(1, 69), status(0, 0)]);
    assert_eq!(announced, [1, 0]);
}
