//! Faults the service must ride out: bad packets, a vanished subscriber, a corrupt model.

use std::time::Duration;

use protocol::{Control, Profile, Reply};

use super::support::*;

/// Datagrams a confused or hostile sender might send.
fn garbage(i: usize) -> Vec<u8> {
    let mut deep = Vec::new();
    for _ in 0..20 {
        deep.extend_from_slice(b"#bundle\0\0\0\0\0\0\0\0\x01");
    }
    match i % 6 {
        0 => vec![0xff; 7],
        1 => b"/mocap/frame\0\0\0\0,ihbb\0\0\0\0\0".to_vec(),
        2 => b"/mocap/frame\0\0\0\0,s\0\0hi\0\0".to_vec(),
        3 => deep,
        4 => b"/nobody/home\0\0\0\0,\0\0\0".to_vec(),
        _ => Vec::new(),
    }
}

#[tokio::test]
async fn a_barrage_of_bad_packets_loses_no_valid_frame() {
    let m = model_file(21);
    let d = start(&m.path, vec![]).await;
    let control = ControlClient::new(d.control).await;
    let rx = Receiver::subscribe(&control, Profile::Compact).await;
    let frames = take_frames(&m.model, 200);
    let collect = rx.spawn_frames(Duration::from_millis(300));
    let mut source = Source::new(d.frames, &m.model).await;
    for (n, xyz) in frames.iter().enumerate() {
        for g in 0..3 {
            source.raw(&garbage(n * 3 + g)).await;
        }
        source.frame(n as i32, xyz).await;
    }
    let got = collect.await.expect("receiver");
    let bad = control.status("bad_packets").await;
    d.stop().await;
    assert_eq!(
        got.iter().map(|g| g.0).collect::<Vec<_>>(),
        (0..200).collect::<Vec<_>>()
    );
    // Empty datagrams may not even reach the socket; every other one is counted.
    assert!(bad >= 400, "bad packets counted: {bad}");
}

#[tokio::test]
async fn a_subscriber_that_disappears_is_dropped_and_the_others_keep_receiving() {
    let m = model_file(22);
    let d = start(&m.path, vec![]).await;
    let control = ControlClient::new(d.control).await;
    let stays = Receiver::subscribe(&control, Profile::Compact).await;
    let leaves = Receiver::subscribe(&control, Profile::Compact).await;
    assert_eq!(control.status("clients").await, 2);
    drop(leaves); // its port now answers with ICMP port unreachable
    let frames = take_frames(&m.model, 150);
    let collect = stays.spawn_frames(Duration::from_millis(300));
    let mut source = Source::new(d.frames, &m.model).await;
    for (n, xyz) in frames.iter().enumerate() {
        source.frame(n as i32, xyz).await;
    }
    let got = collect.await.expect("receiver");
    assert_eq!(got.len(), 150, "the remaining subscriber got every frame");
    assert_eq!(control.status("clients_dropped").await, 1);
    assert_eq!(control.status("clients").await, 1);
    d.stop().await;
}

#[tokio::test]
async fn a_corrupt_model_reload_keeps_the_old_model_and_answers_an_error() {
    let m = model_file(23);
    let d = start(&m.path, vec![]).await;
    let control = ControlClient::new(d.control).await;
    let rx = Receiver::subscribe(&control, Profile::Compact).await;
    let bad = m.dir.path().join("corrupt.json");
    std::fs::write(&bad, b"{\"format_version\": 1, \"labels\": [").expect("write");
    let frames = take_frames(&m.model, 100);
    let collect = rx.spawn_frames(Duration::from_millis(300));
    let mut source = Source::new(d.frames, &m.model).await;
    for (n, xyz) in frames.iter().enumerate().take(50) {
        source.frame(n as i32, xyz).await;
    }
    match control
        .send(&Control::ModelLoad(bad.display().to_string()))
        .await
    {
        Reply::Error { address, message } => {
            assert_eq!(address, "/model/load");
            assert!(message.contains("corrupt.json"), "{message}");
        }
        other => panic!("expected an error, got {other:?}"),
    }
    // A good model swaps in without losing a frame.
    let good = m.dir.path().join("other.json");
    write_model(
        &daemon::loopback::synthetic::random_model(MARKERS, COMPONENTS, 99),
        &good,
    );
    let reply = control
        .send(&Control::ModelLoad(good.display().to_string()))
        .await;
    assert!(matches!(reply, Reply::Confirm(_)), "{reply:?}");
    for (n, xyz) in frames.iter().enumerate().skip(50) {
        source.frame(n as i32, xyz).await;
    }
    let got = collect.await.expect("receiver");
    assert_eq!(control.status("model_swaps").await, 1);
    d.stop().await;
    assert_eq!(
        got.iter().map(|g| g.0).collect::<Vec<_>>(),
        (0..100).collect::<Vec<_>>()
    );
}
