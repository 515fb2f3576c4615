//! A synthetic take through the daemon comes out whole, edited exactly as the offline
//! `emoshift edit` path edits it with the same settings.

use std::time::Duration;

use daemon::offline;
use engine::edit_state::{EditState, DEFAULT_LOWPASS_S};
use engine::layout::LabelMap;
use ica_core::edit::FrameEdit;
use protocol::{Control, Profile, Reply};

use super::support::*;

const FRAMES: usize = 240;

#[tokio::test]
async fn every_frame_comes_out_edited_exactly_as_offline() {
    let m = model_file(11);
    let d = start(&m.path, vec![]).await;
    let control = ControlClient::new(d.control).await;
    let rx = Receiver::subscribe(&control, Profile::Compact).await;
    for c in [
        Control::Ramp(0.0),
        Control::Alpha {
            component: 1,
            value: 0.8,
        },
        Control::Gain {
            component: 2,
            gain: 1.4,
        },
        Control::Target("happy".into()),
        Control::Amount(0.7),
    ] {
        assert!(matches!(control.send(&c).await, Reply::Confirm(_)));
    }
    let frames = take_frames(&m.model, FRAMES);
    let collect = rx.spawn_frames(Duration::from_millis(300));
    let mut source = Source::new(d.frames, &m.model).await;
    for (n, xyz) in frames.iter().enumerate() {
        source.frame(n as i32, xyz).await;
    }
    let got = collect.await.expect("receiver");
    d.stop().await;

    // Offline: the same frames through the code `emoshift edit --translate 1=0.8 --gain 2=1.4
    // --to-emotion happy --amount 0.7 --lowpass 1` runs.
    let mut take = replay::Take::new(m.model.labels().to_vec(), 120.0, 0);
    for xyz in &frames {
        take.push_frame(xyz, &[false; MARKERS]);
    }
    let map = LabelMap::new(m.model.labels(), &take.labels).expect("same labels");
    let projected =
        offline::project_take(&m.model, &offline::to_model_order(&take, &map)).expect("project");
    let mut fixed = FrameEdit::identity(m.model.components());
    fixed.set_offset(1, 0.8).expect("in range");
    fixed.set_gain(2, 1.4).expect("in range");
    let level = m.model.emotion().levels["happy"] as f32;
    let mut emotion = EditState::for_model(&m.model, DEFAULT_LOWPASS_S);
    emotion.set_ramp(0.0);
    emotion
        .set_target("happy", &[level])
        .expect("emotion component");
    emotion.set_amount(0.7).expect("finite");
    let dt = (1.0 / m.model.rate_hz()) as f32;
    let edited = offline::resynthesise(&m.model, &projected, |_, u| {
        fixed.apply(u)?;
        emotion.apply(dt, u);
        Ok(())
    })
    .expect("resynthesise");

    let numbers: Vec<i32> = got.iter().map(|g| g.0).collect();
    assert_eq!(
        numbers,
        (0..FRAMES as i32).collect::<Vec<_>>(),
        "every frame, in order"
    );
    let mut worst = 0.0f32;
    for (f, (_, live)) in got.iter().enumerate() {
        let off = &edited[f * MARKERS * 3..(f + 1) * MARKERS * 3];
        for (a, b) in live.iter().zip(off) {
            worst = worst.max((a - b).abs());
        }
    }
    assert!(worst <= 1e-3, "live and offline differ by {worst} mm");
    // The edit did something: the output is not the input.
    let moved = got[10]
        .1
        .iter()
        .zip(&frames[10])
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f32::max);
    assert!(moved > 0.1, "edit moved markers by only {moved} mm");
}

#[tokio::test]
async fn an_emotion_space_target_and_mix_come_out_as_offline_and_the_list_names_them() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("space.json");
    let model = daemon::loopback::synthetic::random_space_model(MARKERS, COMPONENTS, 5);
    write_model(&model, &path);
    let d = start(&path, vec![]).await;
    let control = ControlClient::new(d.control).await;
    match control.send(&Control::EmotionList).await {
        Reply::EmotionList(list) => {
            assert_eq!(list.components, vec![0, 2]);
            let names: Vec<&str> = list.emotions.iter().map(|e| e.0.as_str()).collect();
            assert_eq!(names, ["angry", "happy", "neutral", "sad"]);
            assert_eq!(list.emotions[0].1, vec![-1.0, 1.5]);
        }
        other => panic!("expected the emotion list, got {other:?}"),
    }
    let mix = Control::Mix(vec![("sad".into(), 1.0), ("angry".into(), 1.0)]);
    for c in [
        Control::Ramp(0.0),
        Control::Target("angry".into()),
        Control::Amount(1.0),
    ] {
        assert!(matches!(control.send(&c).await, Reply::Confirm(_)), "{c:?}");
    }
    let rx = Receiver::subscribe(&control, Profile::Compact).await;
    let frames = take_frames(&model, FRAMES);
    let collect = rx.spawn_frames(Duration::from_millis(300));
    let mut source = Source::new(d.frames, &model).await;
    for (n, xyz) in frames.iter().enumerate() {
        if n == FRAMES / 2 {
            assert!(matches!(control.send(&mix).await, Reply::Confirm(_)));
        }
        source.frame(n as i32, xyz).await;
        // Let the mix land between the same two frames live and offline.
        if n + 1 == FRAMES / 2 {
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
    }
    let got = collect.await.expect("receiver");
    let unknown = Control::Mix(vec![("bored".into(), 1.0)]);
    assert!(matches!(control.send(&unknown).await, Reply::Error { .. }));
    d.stop().await;

    // Offline: `emoshift edit --to-emotion angry --lowpass 1`, then the blend from mid-take.
    let mut take = replay::Take::new(model.labels().to_vec(), 120.0, 0);
    for xyz in &frames {
        take.push_frame(xyz, &[false; MARKERS]);
    }
    let map = LabelMap::new(model.labels(), &take.labels).expect("same labels");
    let projected =
        offline::project_take(&model, &offline::to_model_order(&take, &map)).expect("project");
    let mut emotion = EditState::for_model(&model, DEFAULT_LOWPASS_S);
    emotion.set_ramp(0.0);
    emotion.set_target("angry", &[-1.0, 1.5]).expect("space");
    emotion.set_amount(1.0).expect("finite");
    let dt = (1.0 / model.rate_hz()) as f32;
    let edited = offline::resynthesise(&model, &projected, |f, u| {
        if f == FRAMES / 2 {
            emotion.set_target("sad:0.50,angry:0.50", &[-1.0, 0.0])?;
        }
        emotion.apply(dt, u);
        Ok(())
    })
    .expect("resynthesise");
    assert_eq!(got.len(), FRAMES, "every frame");
    let mut worst = 0.0f32;
    for (f, (_, live)) in got.iter().enumerate() {
        let off = &edited[f * MARKERS * 3..(f + 1) * MARKERS * 3];
        for (a, b) in live.iter().zip(off) {
            worst = worst.max((a - b).abs());
        }
    }
    assert!(worst <= 1e-3, "live and offline differ by {worst} mm");
}
