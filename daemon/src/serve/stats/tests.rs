use super::*;

#[test]
fn status_pairs_name_every_bad_packet_kind_and_the_percentiles() {
    let mut s = Stats::new();
    let osc = Arc::new(InputCounters::named("osc"));
    for _ in 0..3 {
        InputCounters::add(&osc.frames_in);
    }
    osc.bad_packet(DecodeErrorKind::Truncated);
    s.inputs.push(osc);
    Stats::record(&mut s.processed_us, 40);
    s.per_stream.push(StreamStatus {
        key: engine::StreamKey {
            source: "127.0.0.1:5000".parse().expect("literal address"),
            layout_id: 2,
        },
        id: 4,
        name: "alice".into(),
        performer: Some("alice".into()),
        model_markers: 12,
        unmatched_markers: 1,
        target: "happy".into(),
        amount: 0.5,
        frames: 7,
        duplicates: 1,
        stale: 3,
    });
    let pairs = s.pairs();
    let get = |n: &str| {
        pairs
            .iter()
            .find(|(k, _)| k == n)
            .and_then(|(_, v)| v.as_int())
    };
    let text = |n: &str| {
        pairs
            .iter()
            .find(|(k, _)| k == n)
            .and_then(|(_, v)| v.as_text().map(String::from))
    };
    assert_eq!(get("frames_in"), Some(3));
    assert_eq!(get("bad_packets"), Some(1));
    assert_eq!(
        get(&format!("bad_{}", DecodeErrorKind::Truncated.as_str())),
        Some(1)
    );
    assert_eq!(get("processed_p50_us"), Some(40));
    assert_eq!(get("stream/4/frames"), Some(7));
    assert_eq!(get("stream/4/dropped_stale"), Some(3));
    assert_eq!(text("stream/4/name").as_deref(), Some("alice"));
    assert_eq!(text("stream/4/source").as_deref(), Some("127.0.0.1:5000/2"));
    assert_eq!(text("stream/4/emotion").as_deref(), Some("happy"));
}
