//! Issue 34: session variants the emotion method was not built around, each with its truth.

use replay::synth::{generate_session, Synth, SynthParams, Variation};
use replay::Format;

fn params(variation: Variation) -> SynthParams {
    SynthParams {
        seed: 4,
        sentences: 6,
        emotions: ["neutral", "happy", "sad", "angry"]
            .iter()
            .map(|e| e.to_string())
            .collect(),
        emotion_dims: 2,
        variation,
        ..SynthParams::default()
    }
}

fn nv(text: &str) -> replay::synth::NameValue {
    text.parse().expect("name=value")
}

#[test]
fn an_emotion_spoken_in_fewer_sentences_is_still_paired() {
    let p = params(Variation {
        takes: vec![nv("angry=3")],
        ..Variation::default()
    });
    let s = generate_session(&p, Format::C3d).expect("valid");
    let angry: Vec<&str> = s
        .session
        .takes
        .iter()
        .filter(|t| t.emotion == "angry")
        .map(|t| t.sentence.as_str())
        .collect();
    assert_eq!(angry.len(), 3);
    assert_eq!(s.session.takes.len(), 6 * 3 + 3);
    for sentence in angry {
        let others = s
            .session
            .takes
            .iter()
            .filter(|t| t.sentence == sentence && t.emotion != "angry")
            .count();
        assert_eq!(others, 3, "{sentence} is paired");
    }
    assert!(s.truth.mixing.variation.contains("angry in 3 sentences"));
}

#[test]
fn an_emotion_that_speaks_faster_makes_shorter_takes_of_the_same_sentences() {
    let synth = Synth::new(params(Variation {
        speech_rate: vec![nv("angry=1.25")],
        ..Variation::default()
    }))
    .expect("valid");
    let frames = |emotion: &str| -> usize {
        (0..6)
            .map(|s| synth.take_spec(s, emotion).expect("spec").warp.n_frames())
            .sum()
    };
    let ratio = frames("neutral") as f64 / frames("angry") as f64;
    // Each take also draws its own overall pace (0.82 to 1.18).
    assert!(
        (1.05..1.5).contains(&ratio),
        "neutral / angry frames {ratio}"
    );
}

#[test]
fn the_truth_of_an_edit_differs_from_the_take_only_by_the_emotion_fields() {
    // Spread effects and interaction on: the counterfactual is still the same performance with
    // other emotion levels, so the difference is the emotion columns times the level change.
    let synth = Synth::new(params(Variation {
        spread_effects: 1.0,
        interaction: 0.05,
        ..Variation::default()
    }))
    .expect("valid");
    let spec = synth.take_spec(2, "sad").expect("spec");
    let truth_spec = synth.counterfactual(&spec, "happy").expect("spec");
    let (a, b) = (
        synth.render_take(&spec).expect("render").take,
        synth.render_take(&truth_spec).expect("render").take,
    );
    assert_eq!(a.n_frames(), b.n_frames());
    let cols = synth.source_layout();
    let count = cols.count();
    let delta: Vec<f64> = truth_spec
        .emotion_levels
        .iter()
        .zip(&spec.emotion_levels)
        .map(|(x, y)| x - y)
        .collect();
    let happy = synth.take_spec(2, "happy").expect("spec");
    assert_eq!(
        truth_spec.emotion_levels, happy.emotion_levels,
        "happy on sentence 2"
    );
    for f in [0, a.n_frames() / 2] {
        for c in 0..a.n_markers() * 3 {
            let row = &synth.mixing()[c * count..(c + 1) * count];
            let want: f64 = cols.emotions().zip(&delta).map(|(k, d)| row[k] * d).sum();
            let got = f64::from(b.positions[f * a.n_markers() * 3 + c])
                - f64::from(a.positions[f * a.n_markers() * 3 + c]);
            assert!(
                (got - want).abs() < 1e-3,
                "frame {f} channel {c}: {got} vs {want}"
            );
        }
    }
}

#[test]
fn with_a_per_take_intensity_the_truth_is_the_target_s_average_take() {
    let synth = Synth::new(params(Variation {
        take_intensity: 0.5,
        ..Variation::default()
    }))
    .expect("valid");
    let point = synth.point_of("sad").expect("known").to_vec();
    let scales: Vec<f64> = (0..6)
        .map(|s| synth.take_spec(s, "sad").expect("spec").emotion_levels[0] / point[0])
        .collect();
    assert!(scales.iter().all(|k| (0.5..=1.5).contains(k)), "{scales:?}");
    let spread = scales.iter().copied().fold(f64::MIN, f64::max)
        - scales.iter().copied().fold(f64::MAX, f64::min);
    assert!(spread > 0.3, "takes differ in intensity: {scales:?}");
    let spec = synth.take_spec(0, "happy").expect("spec");
    let truth = synth.counterfactual(&spec, "sad").expect("spec");
    let mean = synth.mean_levels("sad").expect("known");
    assert_eq!(truth.emotion_levels, mean);
    let average: f64 = scales.iter().sum::<f64>() / 6.0;
    assert!((mean[0] - point[0] * average).abs() < 1e-12);
}

#[test]
fn variant_knobs_out_of_range_are_refused_with_their_name() {
    for (v, knob) in [
        (
            Variation {
                takes: vec![nv("angry=7")],
                ..Variation::default()
            },
            "takes",
        ),
        (
            Variation {
                speech_rate: vec![nv("sad=3")],
                ..Variation::default()
            },
            "speech rate",
        ),
        (
            Variation {
                take_intensity: 1.0,
                ..Variation::default()
            },
            "take intensity",
        ),
    ] {
        let err = params(v).validate().expect_err("out of range");
        assert!(err.to_string().contains(knob), "{err}");
    }
    let unknown = params(Variation {
        takes: vec![nv("calm=2")],
        ..Variation::default()
    });
    assert!(unknown.validate().is_err());
}
