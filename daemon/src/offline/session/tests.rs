use protocol::SessionControl as C;

use super::script::Script;
use super::*;

fn sitting() -> Sitting {
    Sitting::new(Script::harvard(2), "c3d")
}

#[test]
fn takes_advance_on_acceptance_and_stay_on_refusal() {
    let mut s = sitting();
    assert_eq!(s.takes(), 8);
    assert!(s.handle(C::Stop).is_err());
    let Ok(Step::Record { prompt, replaces }) = s.handle(C::Start) else {
        panic!("start records");
    };
    assert_eq!(
        (prompt.sentence, prompt.emotion.as_str(), replaces),
        (0, "neutral", false)
    );
    assert_eq!(s.status().state, "recording");
    assert!(s.handle(C::Skip).is_err(), "no skip while recording");
    assert_eq!(s.handle(C::Stop), Ok(Step::Stop));
    s.handle_checked(Err("markers missing".into()));
    assert_eq!(s.status().state, "review");
    assert_eq!(s.status().take, 0);
    assert!(matches!(s.handle(C::Retake), Ok(Step::Record { .. })));
    s.handle_checked(Ok(120.0));
    let st = s.status();
    assert_eq!(
        (st.take, st.takes, st.sentence, st.state.as_str()),
        (1, 8, 1, "waiting")
    );
    assert_eq!(
        s.manifest().expect("one take").takes[0].file,
        "s01_neutral.c3d"
    );
}

#[test]
fn a_skipped_take_comes_back_at_the_end_and_resume_continues_where_it_stopped() {
    let mut s = sitting();
    assert_eq!(s.handle(C::Skip), Ok(Step::Moved));
    for _ in 1..8 {
        assert!(matches!(s.handle(C::Start), Ok(Step::Record { .. })));
        s.handle(C::Stop).expect("recording");
        s.handle_checked(Ok(100.0));
    }
    assert_eq!(s.cursor(), 0, "the skipped take is offered again");
    let manifest = s.manifest().expect("takes");
    assert_eq!(manifest.takes.len(), 7);
    let resumed = Sitting::resume(Script::harvard(2), "c3d", &manifest);
    assert_eq!((resumed.cursor(), resumed.accepted()), (0, 7));
    assert_eq!(resumed.manifest().expect("takes"), manifest);
    s.handle(C::Start).expect("start");
    s.handle(C::Stop).expect("stop");
    s.handle_checked(Ok(100.0));
    assert_eq!(s.status().state, "done");
    assert_eq!(s.status().take, 8);
    // Retake from done: the last accepted take, replacing it.
    assert!(matches!(
        s.handle(C::Retake),
        Ok(Step::Record { replaces: true, .. })
    ));
}

#[test]
fn redo_offers_named_takes_again_and_refuses_unknown_names() {
    let mut s = sitting();
    for _ in 0..8 {
        s.handle(C::Start).expect("start");
        s.handle(C::Stop).expect("stop");
        s.handle_checked(Ok(120.0));
    }
    assert_eq!(s.status().state, "done");
    s.redo(&["s02_sad".into(), "s01_happy.c3d".into()])
        .expect("known takes");
    // The old takes count until their new ones pass: a finish now still trains on 8.
    assert_eq!((s.accepted(), s.to_redo()), (8, 2));
    assert_eq!(s.status().state, "waiting");
    assert_eq!(s.manifest().expect("takes").takes.len(), 8);
    assert_eq!(s.prompt().file_name("c3d"), "s01_happy.c3d");
    assert!(matches!(
        s.handle(C::Start),
        Ok(Step::Record { replaces: true, .. })
    ));
    assert!(s.redo(&["s09_sad".into()]).is_err());
}

#[test]
fn a_finish_offers_its_redo_which_prompts_just_those_takes_or_a_second_finish_closes() {
    let mut s = sitting();
    assert!(
        s.handle(C::Redo).is_err(),
        "nothing offered before a finish"
    );
    for _ in 0..8 {
        s.handle(C::Start).expect("start");
        s.handle(C::Stop).expect("stop");
        s.handle_checked(Ok(120.0));
    }
    assert_eq!(s.handle(C::Finish), Ok(Step::Finish));
    s.offer(&["s02_sad.c3d".into(), "s02_neutral.c3d".into()])
        .expect("known takes");
    assert_eq!(s.offered(), ["s02_sad.c3d", "s02_neutral.c3d"]);
    let mut declined = s.clone();
    assert_eq!(declined.handle(C::Finish), Ok(Step::Close));
    assert_eq!(s.handle(C::Redo), Ok(Step::Moved));
    assert!(s.offered().is_empty());
    let mut redone = Vec::new();
    while s.status().state != "done" {
        redone.push(s.prompt().file_name("c3d"));
        s.handle(C::Start).expect("start");
        s.handle(C::Stop).expect("stop");
        s.handle_checked(Ok(120.0));
    }
    redone.sort();
    assert_eq!(redone, ["s02_neutral.c3d", "s02_sad.c3d"]);
    assert_eq!(s.accepted(), 8);
    assert_eq!(s.handle(C::Finish), Ok(Step::Finish), "trains again");
    s.offer(&["s01_sad".into()]).expect("a take");
    s.handle(C::Back).expect("back");
    assert_eq!(
        s.handle(C::Finish),
        Ok(Step::Finish),
        "another control declined the offer"
    );
}

#[test]
fn issue_37_a_resumed_session_keeps_the_ranges_written_into_its_manifest() {
    let mut s = sitting();
    assert_eq!(s.handle(C::Skip), Ok(Step::Moved));
    for _ in 1..3 {
        s.handle(C::Start).expect("start");
        s.handle(C::Stop).expect("stop");
        s.handle_checked(Ok(100.0));
    }
    let mut manifest = s.manifest().expect("takes");
    manifest.takes[1].start = Some(replay::session::FrameOrTime::Frame(40));
    manifest.takes[1].end = Some(replay::session::FrameOrTime::Seconds(2.5));
    let mut resumed = Sitting::resume(Script::harvard(2), "c3d", &manifest);
    assert_eq!(resumed.manifest().expect("takes"), manifest);
    resumed.handle(C::Start).expect("start");
    resumed.handle(C::Stop).expect("stop");
    resumed.handle_checked(Ok(100.0));
    let written = resumed.manifest().expect("takes");
    assert_eq!(written.takes.len(), 3);
    assert_eq!(written.takes[2], manifest.takes[1], "kept as edited");
    assert!(written.takes[0].range().is_whole(), "a new take is whole");
}
