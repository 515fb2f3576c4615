//! A synthetic take through the daemon comes out whole, edited exactly as the offline
//! `emoshift edit` path edits it with the same settings.

use std::time::Duration;

use daemon::layout::LabelMap;
use daemon::offline;
use daemon::serve::edit_state::{EditState, DEFAULT_LOWPASS_S};
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
    let mut emotion = EditState::new(
        m.model.components(),
        m.model.emotion().component,
        DEFAULT_LOWPASS_S,
    );
    emotion.set_ramp(0.0);
    emotion
        .set_target("happy", level)
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
