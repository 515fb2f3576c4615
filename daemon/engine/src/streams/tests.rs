use super::*;

#[test]
fn performers_match_on_source_and_layout() {
    let a: SocketAddr = "127.0.0.1:7000".parse().expect("addr");
    let b: SocketAddr = "127.0.0.1:7001".parse().expect("addr");
    let p: Performer = Performer {
        name: "alice".into(),
        source: Some(a),
        layout: None,
        markerset: None,
        model: None,
        target: None,
        amount: None,
    };
    let face = Performer {
        markerset: Some("Face".into()),
        ..p.clone()
    };
    let k = StreamKey {
        source: a,
        layout_id: 0,
    };
    assert!(face.owns_stream(&k, Some("Face")));
    assert!(!face.owns_stream(&k, Some("Body")) && !face.owns(&k));
    assert!(p.owns(&StreamKey {
        source: a,
        layout_id: 3
    }));
    assert!(!p.owns(&StreamKey {
        source: b,
        layout_id: 3
    }));
}
