//! The emotion space of the synthetic generator (issue 13, part 4): k emotion directions, each
//! emotion a point in them, its truth, and renders at any level vector with a take's timing.

use replay::synth::sources::{DRIFT_AMPLITUDE, INTENSITY_SPREAD};
use replay::synth::space::SPARE_SEPARATION;
use replay::synth::{
    generate_session, load_truth, write_session, EmotionPoint, MixingTruth, Synth, SynthError,
    SynthParams, SynthSession, TakeTruth,
};
use replay::Format;

fn names(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

fn params(dims: usize, emotions: &[&str], sentences: usize) -> SynthParams {
    SynthParams {
        seed: 5,
        sentences,
        emotion_dims: dims,
        emotions: names(emotions),
        ..SynthParams::default()
    }
}

fn session(p: &SynthParams) -> SynthSession {
    generate_session(p, Format::C3d).expect("valid params")
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// Every take's emotion sources sit at its emotion's point x intensity, and the mean over an
/// emotion's takes sits at the point within the intensity spread and the drift.
fn check_points(s: &SynthSession, dims: usize) {
    let m = &s.truth.mixing;
    let cols = m.emotion_columns();
    assert_eq!(cols.len(), dims);
    assert_eq!(m.role_indices("emotion"), cols);
    for e in &m.emotions {
        let point = m.point_of(&e.name).expect("listed");
        assert_eq!(point.len(), dims);
        let takes: Vec<&TakeTruth> = s
            .truth
            .takes
            .iter()
            .filter(|t| t.emotion == e.name)
            .collect();
        assert!(takes.len() >= 3);
        let mut grand = vec![0.0; dims];
        for t in &takes {
            let levels = t.levels();
            assert_eq!(levels[0], t.emotion_level);
            for d in 0..dims {
                let spread = INTENSITY_SPREAD * point[d].abs() + 1e-12;
                assert!((levels[d] - point[d]).abs() <= spread, "{} {d}", t.name);
                let avg = mean(&t.source(cols[d]));
                assert!(
                    (avg - levels[d]).abs() < DRIFT_AMPLITUDE,
                    "{} {d}: {avg}",
                    t.name
                );
                grand[d] += avg / takes.len() as f64;
            }
        }
        for d in 0..dims {
            let tol = INTENSITY_SPREAD * point[d].abs() + DRIFT_AMPLITUDE;
            assert!(
                (grand[d] - point[d]).abs() < tol,
                "{}: mean source {grand:?}, point {point:?}",
                e.name
            );
        }
    }
    // Well-separated points, so the space is real test truth.
    for (i, a) in m.emotions.iter().enumerate() {
        for b in &m.emotions[..i] {
            let d = distance(&a.point(), &b.point());
            assert!(d > 0.8, "{} and {} only {d} apart", a.name, b.name);
        }
    }
}

#[test]
fn two_directions_put_four_emotions_at_their_points() {
    let s = session(&params(2, &["neutral", "happy", "sad", "angry"], 4));
    check_points(&s, 2);
    let m = &s.truth.mixing;
    assert_eq!(m.point_of("sad"), Some(vec![-0.6, -0.8]));
    assert_eq!(m.point_of("angry"), Some(vec![-0.2, 1.0]));
    assert_eq!(m.source_index("emotion_1"), Some(5));
    assert_eq!(m.source_index("brow_raise"), Some(6));
    assert_eq!(s.takes.len(), 16);
}

#[test]
fn three_directions_put_six_emotions_at_their_points() {
    let six = ["neutral", "happy", "sad", "angry", "surprised", "fear"];
    let s = session(&params(3, &six, 3));
    check_points(&s, 3);
    let m = &s.truth.mixing;
    assert_eq!(m.emotion_columns(), vec![4, 5, 6]);
    assert_eq!(m.sources.len(), 15);
    assert_eq!(m.role_indices("head"), (9..15).collect::<Vec<_>>());
    // Each take has its own timing.
    let frames: Vec<usize> = s.truth.takes[..6].iter().map(|t| t.n_frames()).collect();
    assert!(frames.windows(2).any(|w| w[0] != w[1]), "{frames:?}");
}

/// Residual norm of `v` after projecting out `basis` (orthonormal).
fn residual(v: &[f64], basis: &[Vec<f64>]) -> Vec<f64> {
    let mut r = v.to_vec();
    for b in basis {
        let dot: f64 = r.iter().zip(b).map(|(x, y)| x * y).sum();
        r.iter_mut().zip(b).for_each(|(x, y)| *x -= dot * y);
    }
    r
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Markers whose displacement under column `c` exceeds 0.5 mm, counted per region.
fn regions_moved(m: &MixingTruth, c: usize) -> usize {
    m.regions
        .values()
        .filter(|labels| {
            labels.iter().any(|l| {
                let i = m.labels.iter().position(|x| x == l).expect("label");
                norm(&(0..3).map(|a| m.matrix[i * 3 + a][c]).collect::<Vec<_>>()) > 0.5
            })
        })
        .count()
}

#[test]
fn emotion_columns_are_independent_and_each_moves_several_regions() {
    let synth = Synth::new(params(3, &["neutral"], 1)).expect("valid");
    let m = synth.mixing_truth();
    // Every column (speech, emotions, brows, blink, head) keeps a sizable part of its own
    // after projecting out the others: the matrix has full column rank, well conditioned.
    let mut basis: Vec<Vec<f64>> = Vec::new();
    let order: Vec<usize> = (0..m.sources.len()).collect();
    for &c in &order {
        let col = m.column(c);
        let r = residual(&col, &basis);
        let share = norm(&r) / norm(&col);
        assert!(share > 0.2, "{} keeps only {share:.3}", m.sources[c].name);
        let n = norm(&r);
        basis.push(r.iter().map(|x| x / n).collect());
    }
    for c in m.emotion_columns() {
        let moved = regions_moved(&m, c);
        assert!(moved >= 4, "{} moves {moved} regions", m.sources[c].name);
    }
}

#[test]
fn counterfactuals_at_the_same_timing_differ_by_mixing_times_level_change() {
    let six = ["neutral", "happy", "sad", "angry", "surprised", "fear"];
    let synth = Synth::new(params(3, &six, 2)).expect("valid");
    let m = synth.mixing_truth();
    let sad = synth.take_spec(1, "sad").expect("valid");
    let angry = synth.take_spec(1, "angry").expect("valid");
    assert_ne!(angry.warp, sad.warp);
    let blend = synth.blend(&[("sad", 0.5), ("angry", 0.5)]).expect("known");
    assert_eq!(
        m.blend(&[("sad", 0.5), ("angry", 0.5)]),
        Some(blend.clone())
    );
    let variants = [
        angry.with_timing_of(&sad),
        sad.clone().with_levels(blend),
        sad.clone().with_levels(vec![0.0; 3]),
    ];
    let a = synth.render_take(&sad).expect("renders");
    let cols = m.emotion_columns();
    for spec in variants {
        let b = synth.render_take(&spec).expect("renders");
        assert_eq!(a.take.n_frames(), b.take.n_frames());
        assert_eq!(b.truth.levels(), spec.emotion_levels);
        let delta: Vec<f64> = (0..3)
            .map(|d| spec.emotion_levels[d] - sad.emotion_levels[d])
            .collect();
        let shift = m.emotion_displacement(&delta).expect("three levels");
        assert!(norm(&shift) > 5.0, "a visible change");
        for f in 0..a.take.n_frames() {
            let (fa, fb) = (a.take.frame(f), b.take.frame(f));
            for (c, want) in shift.iter().enumerate() {
                let diff = f64::from(fb[c]) - f64::from(fa[c]);
                assert!((diff - want).abs() < 1e-3, "frame {f} channel {c}");
            }
            for k in 0..m.sources.len() {
                let want = cols.iter().position(|&e| e == k).map_or(0.0, |d| delta[d]);
                let got = b.truth.sources[f][k] - a.truth.sources[f][k];
                assert!((got - want).abs() < 1e-12);
            }
        }
    }
    assert!(matches!(
        synth.render_take(&sad.clone().with_levels(vec![1.0])),
        Err(SynthError::LevelDims {
            expected: 3,
            got: 1
        })
    ));
    assert!(matches!(
        synth.render_take(&sad.with_levels(vec![0.0, f64::NAN, 0.0])),
        Err(SynthError::NonFiniteLevel(_))
    ));
}

#[test]
fn spare_and_explicit_points_in_two_directions() {
    let list = ["calm", "happy", "bored", "sad", "proud", "neutral", "tired"];
    let p = SynthParams {
        emotion_points: vec!["calm=0.3,0.4".parse().expect("valid")],
        ..params(2, &list, 1)
    };
    let synth = Synth::new(p).expect("valid");
    assert_eq!(synth.point_of("calm").expect("listed"), &[0.3, 0.4]);
    assert_eq!(synth.point_of("happy").expect("listed"), &[1.0, 0.0]);
    let points: Vec<&[f64]> = list
        .iter()
        .map(|e| synth.point_of(e).expect("listed"))
        .collect();
    for i in [2, 4, 6] {
        for (j, q) in points.iter().enumerate() {
            if i != j {
                let d = distance(points[i], q);
                assert!(
                    d >= SPARE_SEPARATION - 1e-9,
                    "{} vs {}: {d}",
                    list[i],
                    list[j]
                );
            }
        }
    }
    // Deterministic: the same list gives the same spare points.
    let again = Synth::new(synth.params().clone()).expect("valid");
    assert_eq!(again.point_of("tired").ok(), synth.point_of("tired").ok());
}

#[test]
fn bad_emotion_spaces_are_refused_naming_the_value() {
    let point = |t: &str| t.parse::<EmotionPoint>().expect("parses");
    let cases: Vec<(SynthParams, &str)> = vec![
        (params(0, &["neutral"], 1), "got 0"),
        (params(4, &["neutral"], 1), "got 4"),
        (
            SynthParams {
                emotion_points: vec![point("happy=1,0")],
                ..params(3, &["happy"], 1)
            },
            "has 2 coordinates",
        ),
        (
            SynthParams {
                emotion_points: vec![point("joy=1,0")],
                ..params(2, &["happy"], 1)
            },
            "\"joy\"",
        ),
        (
            SynthParams {
                emotion_points: vec![point("happy=1,0"), point("happy=0,1")],
                ..params(2, &["happy"], 1)
            },
            "two points",
        ),
        (
            SynthParams {
                emotion_points: vec![EmotionPoint {
                    name: "happy".into(),
                    point: vec![f64::INFINITY, 0.0],
                }],
                ..params(2, &["happy"], 1)
            },
            "inf",
        ),
    ];
    for (p, needle) in cases {
        let err = Synth::new(p).expect_err("invalid");
        assert!(err.to_string().contains(needle), "{err} lacks {needle}");
    }
}

#[test]
fn one_direction_takes_explicit_levels() {
    let p = SynthParams {
        emotion_points: vec!["happy=2".parse().expect("valid")],
        ..params(1, &["neutral", "happy", "calm"], 1)
    };
    let synth = Synth::new(p).expect("valid");
    assert_eq!(synth.level_of("happy").expect("listed"), 2.0);
    assert_eq!(synth.level_of("calm").expect("listed"), 0.5);
    assert_eq!(synth.mixing_truth().sources.len(), 13);
}

#[test]
fn written_space_reads_back_and_old_truth_still_loads() {
    let dir = tempfile::tempdir().expect("temp dir");
    let p = params(2, &["neutral", "angry"], 1);
    write_session(dir.path(), &p, Format::Trc).expect("writes");
    let truth = load_truth(dir.path()).expect("loads");
    assert_eq!(truth.mixing.point_of("angry"), Some(vec![-0.2, 1.0]));
    assert_eq!(truth.mixing.emotion_columns, vec![4, 5]);
    assert_eq!(truth.takes[1].emotion_levels.len(), 2);
    // Truth written by the one-source generator has no points, columns or level vectors.
    let one = session(&params(1, &["neutral", "happy"], 1)).truth;
    let mut mixing = serde_json::to_value(&one.mixing).expect("serialises");
    mixing
        .as_object_mut()
        .expect("object")
        .remove("emotion_columns");
    for e in mixing["emotions"].as_array_mut().expect("list") {
        e.as_object_mut().expect("object").remove("point");
    }
    let old: MixingTruth = serde_json::from_value(mixing).expect("old mixing loads");
    assert_eq!(old.emotion_columns(), vec![4]);
    assert_eq!(old.point_of("happy"), Some(vec![1.0]));
    let mut take = serde_json::to_value(&one.takes[1]).expect("serialises");
    take.as_object_mut()
        .expect("object")
        .remove("emotion_levels");
    let old: TakeTruth = serde_json::from_value(take).expect("old take loads");
    assert_eq!(old.levels(), one.takes[1].levels());
}
