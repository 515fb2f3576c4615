//! `serve` without a model (issue 37): a stage starts the daemon before the performer's model
//! exists. Frames pass through unedited, under the same frame numbers, to subscribers and to a
//! recording; edits are refused naming `/model/load`; `/model/load` later edits from the next
//! frame, in the same recording, without losing a frame.

use std::time::Duration;

use protocol::{Control, Profile, Reply};

use super::support::*;

/// Frames before and after the model is loaded.
const EACH: usize = 60;

fn message(reply: &Reply) -> &str {
    match reply {
        Reply::Error { message, .. } => message,
        other => panic!("expected an error, got {other:?}"),
    }
}

async fn send_frames(source: &mut Source, frames: &[Vec<f32>], first: usize) {
    for (k, xyz) in frames.iter().enumerate() {
        source.frame((first + k) as i32, xyz).await;
    }
}

#[tokio::test]
async fn without_a_model_frames_pass_through_and_record_until_one_is_loaded() {
    let m = model_file(41);
    let d = start_on(None, vec![]).await;
    let control = ControlClient::new(d.control).await;
    assert_eq!(control.status_text("model").await, "none");
    let refused = control.send(&Control::Target("happy".into())).await;
    assert!(message(&refused).contains("/model/load"), "{refused:?}");
    assert_eq!(control.status("control_refused").await, 1);

    let (out, raw_out) = (
        m.dir.path().join("live.trc"),
        m.dir.path().join("input.trc"),
    );
    let start = Control::RecordStart {
        path: out.display().to_string(),
        raw: Some(raw_out.display().to_string()),
        overwrite: false,
    };
    assert!(matches!(control.send(&start).await, Reply::Confirm(_)));
    let rx = Receiver::subscribe(&control, Profile::Compact).await;
    let frames = take_frames(&m.model, 2 * EACH);
    let collect = rx.spawn_frames(Duration::from_millis(300));
    let mut source = Source::new(d.frames, &m.model).await;
    send_frames(&mut source, &frames[..EACH], 0).await;
    let before = collect.await.expect("receiver");
    let numbers: Vec<i32> = before.iter().map(|f| f.0).collect();
    assert_eq!(
        numbers,
        (0..EACH as i32).collect::<Vec<_>>(),
        "every frame, same numbers"
    );
    for (n, xyz) in &before {
        assert_eq!(
            xyz, &frames[*n as usize],
            "frame {n} passes through unedited"
        );
    }

    // A model whose markers the stream lacks is refused as with any model swap.
    let other = m.dir.path().join("bigger.json");
    write_model(
        &daemon::loopback::synthetic::random_model(MARKERS + 2, 3, 5),
        &other,
    );
    let mismatch = control
        .send(&Control::ModelLoad(other.display().to_string()))
        .await;
    assert!(message(&mismatch).contains("lacks 2"), "{mismatch:?}");
    assert_eq!(control.status_text("model").await, "none");

    let load = Control::ModelLoad(m.path.display().to_string());
    assert!(matches!(control.send(&load).await, Reply::Confirm(_)));
    for c in [
        Control::Ramp(0.0),
        Control::Target("happy".into()),
        Control::Amount(1.0),
    ] {
        let r = control.send(&c).await;
        assert!(matches!(r, Reply::Confirm(_)), "{c:?}: {r:?}");
    }
    let collect = rx.spawn_frames(Duration::from_millis(300));
    send_frames(&mut source, &frames[EACH..], EACH).await;
    let after = collect.await.expect("receiver");
    let numbers: Vec<i32> = after.iter().map(|f| f.0).collect();
    assert_eq!(numbers, (EACH as i32..2 * EACH as i32).collect::<Vec<_>>());
    for (n, xyz) in &after {
        let moved = xyz
            .iter()
            .zip(&frames[*n as usize])
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        assert!(
            moved > 0.1,
            "frame {n} is edited once the model is in ({moved} mm)"
        );
    }
    assert!(matches!(
        control.send(&Control::RecordStop).await,
        Reply::Confirm(_)
    ));
    assert_eq!(control.status("frames_out").await, 2 * EACH as i64);
    d.stop().await;

    // One file across the swap (same labels): the first half as received, the rest edited.
    let take = replay::load(&out).expect("the recording reads");
    assert_eq!(take.n_frames(), 2 * EACH);
    assert_eq!(take.labels, m.model.labels());
    let width = MARKERS * 3;
    for (n, sent) in frames.iter().enumerate() {
        let got = &take.positions[n * width..(n + 1) * width];
        if n < EACH {
            assert_eq!(got, &sent[..], "recorded frame {n} as received");
        } else {
            assert_ne!(got, &sent[..], "recorded frame {n} edited");
        }
    }
    let raw = replay::load(&raw_out).expect("the raw recording reads");
    assert_eq!(raw.n_frames(), 2 * EACH);
    assert_eq!(take.first_frame, raw.first_frame, "the same frame numbers");
    assert_eq!(raw.positions, frames.concat(), "the raw input, whole");
}
