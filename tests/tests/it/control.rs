//! Control changes take effect at a frame boundary and glide in over their ramp.

use std::time::Duration;

use protocol::{Control, Profile, Reply};

use super::support::*;

#[tokio::test]
async fn an_alpha_change_glides_in_over_the_ramp() {
    let m = model_file(5);
    let d = start(&m.path, vec![]).await;
    let control = ControlClient::new(d.control).await;
    let with = Receiver::subscribe(&control, Profile::Components).await;
    let frames = take_frames(&m.model, 120);
    let collect = with.spawn_components(Duration::from_millis(200));
    let mut source = Source::new(d.frames, &m.model).await;
    for (n, xyz) in frames.iter().enumerate().take(60) {
        source.frame(n as i32, xyz).await;
    }
    let before = collect.await.expect("receiver");
    assert_eq!(before.len(), 60);
    // 0.25 s at 120 Hz = 30 frames.
    assert!(matches!(
        control.send(&Control::Ramp(0.25)).await,
        Reply::Confirm(_)
    ));
    let alpha = Control::Alpha {
        component: 3,
        value: 4.0,
    };
    assert!(matches!(control.send(&alpha).await, Reply::Confirm(_)));
    let collect = with.spawn_components(Duration::from_millis(200));
    for (n, xyz) in frames.iter().enumerate().skip(60) {
        source.frame(n as i32, xyz).await;
    }
    let after = collect.await.expect("receiver");
    d.stop().await;
    assert_eq!(after.len(), 60);

    // The unedited component, from the same processor offline.
    let mut proc = engine::frame::FrameProcessor::new(&m.model);
    let mut u = vec![0.0; COMPONENTS];
    let base: Vec<f32> = frames
        .iter()
        .map(|xyz| {
            proc.project(xyz, &[false; MARKERS], &mut u).expect("sizes");
            u[3]
        })
        .collect();
    let offset: Vec<f32> = after
        .iter()
        .enumerate()
        .map(|(i, a)| a[3] - base[60 + i])
        .collect();
    assert!(
        offset[0].abs() < 0.05,
        "the glide starts from the old value: {}",
        offset[0]
    );
    assert!(
        offset[10] > 0.2 && offset[10] < 3.8,
        "mid-ramp at frame 10: {}",
        offset[10]
    );
    for w in offset.windows(2) {
        assert!(w[1] >= w[0] - 1e-3, "monotonic glide: {offset:?}");
        // Smoothstep over 30 frames: at most 1.5x the linear step of 4/30.
        assert!(w[1] - w[0] < 0.21, "a pop of {} in {offset:?}", w[1] - w[0]);
    }
    for o in &offset[31..] {
        assert!((o - 4.0).abs() < 1e-3, "settled at the new alpha: {o}");
    }
}

#[tokio::test]
async fn refused_controls_are_answered_with_the_reason() {
    let m = model_file(5);
    let d = start(&m.path, vec![]).await;
    let control = ControlClient::new(d.control).await;
    let bad = Control::Gain {
        component: 99,
        gain: 1.0,
    };
    match control.send(&bad).await {
        Reply::Error { address, message } => {
            assert_eq!(address, "/component/gain");
            assert!(message.contains("99"), "{message}");
        }
        other => panic!("expected an error, got {other:?}"),
    }
    match control.send(&Control::Target("furious".into())).await {
        Reply::Error { message, .. } => assert!(message.contains("furious"), "{message}"),
        other => panic!("expected an error, got {other:?}"),
    }
    d.stop().await;
}
