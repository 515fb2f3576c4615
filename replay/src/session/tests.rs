use super::*;

/// The error and its causes, as the binary prints them.
fn chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        text = format!("{text}: {s}");
        source = s.source();
    }
    text
}

#[test]
fn manifests_reject_bad_input_and_resolve_paths() {
    let missing = "rate_hz = 120\n[[take]]\nfile = \"a.c3d\"\nsentence = \"s01\"\n";
    let err = Session::parse(missing).expect_err("missing emotion");
    assert!(chain(&err).contains("emotion"), "{err}");
    let unknown = format!("{missing}emotion = \"happy\"\nmood = \"x\"\n");
    assert!(chain(&Session::parse(&unknown).expect_err("unknown field")).contains("mood"));
    assert!(matches!(
        Session::parse("rate_hz = 120\n"),
        Err(SessionError::NoTakes)
    ));
    let no_rate = missing.replace("rate_hz = 120\n", "") + "emotion = \"happy\"\n";
    let err = Session::parse(&no_rate).expect_err("no rate");
    assert!(matches!(err, SessionError::MissingRate), "{err}");
    assert!(
        err.to_string().contains("rate_hz = 120"),
        "says what to write: {err}"
    );
    let zero = missing.replace("120", "0") + "emotion = \"happy\"\n";
    assert!(matches!(
        Session::parse(&zero),
        Err(SessionError::BadRate(_))
    ));

    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("session.toml");
    std::fs::write(&path, format!("{missing}emotion = \"happy\"\n")).expect("write");
    let loaded = Session::load(&path).expect("loads");
    assert_eq!(loaded.take_paths(), vec![dir.path().join("a.c3d")]);

    let labels = ["UpperLip1", "BrowL1"];
    let empty = Regions::parse("mouth = [\"Lip*\"]").expect("parses");
    assert!(matches!(
        empty.resolve(&labels),
        Err(SessionError::EmptyRegion { .. })
    ));
    let typo = Regions::parse("mouth = [\"UpperLip*\", \"UperLip2\"]").expect("parses");
    let err = typo.resolve(&labels).expect_err("unknown literal label");
    assert!(err.to_string().contains("UperLip2"));
    assert!(err.to_string().contains("its markers are"), "{err}");
    // Labels are case-sensitive; the message names what the pattern meant.
    let case = Regions::parse("brows = [\"BROW*\"]").expect("parses");
    let err = case.resolve(&labels).expect_err("case differs").to_string();
    assert!(
        err.contains("case-sensitive") && err.contains("\"BrowL1\""),
        "{err}"
    );
    let case = Regions::parse("brows = [\"browl1\"]").expect("parses");
    let err = case.resolve(&labels).expect_err("case differs").to_string();
    assert!(err.contains("the take has \"BrowL1\""), "{err}");
    assert!(Regions::parse("mouth = [\"[\"]").is_err());
    let ok = Regions::parse("mouth = [\"UpperLip*\"]\nbrows = [\"BrowL1\"]").expect("parses");
    let r = ok.resolve(&labels).expect("resolves");
    assert_eq!(r["mouth"], vec![0]);
    assert_eq!(r["brows"], vec![1]);
}

#[test]
fn issue_37_take_ranges_parse_round_trip_and_refuse_a_backwards_range() {
    let take = "[[take]]\nfile = \"a.c3d\"\nsentence = \"s01\"\nemotion = \"happy\"\n";
    let text = format!("rate_hz = 120\n{take}start = 240\nend = \"6.5s\"\n");
    let session = Session::parse(&text).expect("parses");
    let range = session.takes[0].range();
    assert_eq!(range.start, Some(FrameOrTime::Frame(240)));
    assert_eq!(range.end, Some(FrameOrTime::Seconds(6.5)));
    let again = Session::parse(&session.to_toml().expect("writes")).expect("reads back");
    assert_eq!(again, session);
    let whole = Session::parse(&format!("rate_hz = 120\n{take}")).expect("parses");
    assert!(whole.takes[0].range().is_whole());
    assert!(!whole.to_toml().expect("writes").contains("start"));

    let backwards = format!("rate_hz = 120\n{take}start = \"3s\"\nend = \"1.5s\"\n");
    let err = Session::parse(&backwards).expect_err("end before start");
    assert!(matches!(err, SessionError::BadRange { .. }), "{err}");
    let text = chain(&err);
    assert!(text.contains("\"a.c3d\"") && text.contains("end = 1.5s is before start = 3s"));
    let float = format!("rate_hz = 120\n{take}start = 2.5\n");
    let err = chain(&Session::parse(&float).expect_err("a bare float"));
    assert!(err.contains("\"2.5s\""), "says what to write: {err}");
}
