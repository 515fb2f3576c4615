use super::*;

fn names(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

#[test]
fn knobs_are_checked_against_the_session() {
    let emotions = names(&["neutral", "happy", "angry"]);
    let ok = Variation {
        take_intensity: 0.4,
        takes: vec!["angry=3".parse().expect("parses")],
        speech_rate: vec!["happy=1.2".parse().expect("parses")],
        ..Variation::default()
    };
    assert!(ok.validate(&emotions, 8).is_ok());
    assert_eq!(ok.rate_of("happy"), 1.2);
    assert_eq!(ok.rate_of("angry"), 1.0);
    assert_eq!(ok.takes_of("angry"), Some(3));
    let bad = |v: Variation| v.validate(&emotions, 8).is_err();
    assert!(bad(Variation {
        takes: vec!["angry=9".parse().expect("parses")],
        ..Variation::default()
    }));
    assert!(bad(Variation {
        takes: vec!["angry=2.5".parse().expect("parses")],
        ..Variation::default()
    }));
    assert!(bad(Variation {
        speech_rate: vec!["calm=1.1".parse().expect("parses")],
        ..Variation::default()
    }));
    assert!(bad(Variation {
        take_intensity: f64::NAN,
        ..Variation::default()
    }));
    assert!("angry".parse::<NameValue>().is_err());
    assert!("angry=x".parse::<NameValue>().is_err());
}

#[test]
fn a_subset_of_sentences_has_the_count_asked_for_and_depends_on_the_seed() {
    let a = spoken_in(1, "angry", Some(3), 8);
    assert_eq!(a.iter().filter(|&&s| s).count(), 3);
    assert_eq!(spoken_in(1, "angry", None, 8), vec![true; 8]);
    let draws: Vec<Vec<bool>> = (0..6).map(|s| spoken_in(s, "angry", Some(3), 8)).collect();
    assert!(
        draws.iter().any(|d| *d != a),
        "the seed picks the sentences"
    );
}
