//! The synthetic face generator: determinism, geometry and regions, the source model and its
//! ground truth, paired timing, counterpart rendering, and the session files.

use replay::session::{Regions, Session};
use replay::synth::{
    generate_session, load_truth, write_session, MixingTruth, Synth, SynthError, SynthParams,
    SynthSession, TakeTruth, NOISE_STD_MM,
};
use replay::{Format, Take};

fn params(sentences: usize) -> SynthParams {
    SynthParams {
        sentences,
        seed: 11,
        ..SynthParams::default()
    }
}

fn session(sentences: usize) -> SynthSession {
    generate_session(&params(sentences), Format::C3d).expect("default params are valid")
}

/// take - (rest + mixing · sources), every coordinate of every frame.
fn residuals(mixing: &MixingTruth, take: &Take, truth: &TakeTruth) -> Vec<f64> {
    let mut out = Vec::new();
    for f in 0..take.n_frames() {
        let frame = take.frame(f);
        for (c, row) in mixing.matrix.iter().enumerate() {
            let model: f64 = row.iter().zip(&truth.sources[f]).map(|(a, s)| a * s).sum();
            out.push(f64::from(frame[c]) - mixing.rest[c] - model);
        }
    }
    out
}

fn mean_std(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
    (mean, var.sqrt())
}

fn dist(a: &[f32], i: usize, j: usize) -> f64 {
    (0..3)
        .map(|k| f64::from(a[i * 3 + k] - a[j * 3 + k]).powi(2))
        .sum::<f64>()
        .sqrt()
}

#[test]
fn same_seed_gives_identical_sessions_and_another_seed_does_not() {
    let a = session(2);
    let b = session(2);
    assert_eq!(a.takes, b.takes);
    assert_eq!(a.truth, b.truth);
    assert_eq!(a.session, b.session);
    let c = generate_session(
        &SynthParams {
            seed: 12,
            ..params(2)
        },
        Format::C3d,
    )
    .expect("valid");
    assert_ne!(a.takes[0].positions, c.takes[0].positions);
}

#[test]
fn face_has_109_labelled_markers_in_named_regions() {
    let s = session(1);
    let labels = &s.takes[0].labels;
    assert_eq!(labels.len(), 109);
    for l in [
        "MouthCornerL",
        "UpperLip1",
        "BrowL2",
        "LidUpperR",
        "HeadFront",
        "NoseTip",
    ] {
        assert!(labels.iter().any(|x| x == l), "missing {l}");
    }
    let regions = s
        .regions
        .resolve(labels)
        .expect("generated regions resolve");
    let need = [
        ("mouth", 12),
        ("eyebrows", 8),
        ("eyelids", 4),
        ("cheeks", 8),
        ("jaw", 4),
        ("forehead", 4),
        ("nose", 3),
        ("head_reference", 4),
    ];
    for (name, min) in need {
        let n = regions.get(name).map_or(0, Vec::len);
        assert!(n >= min, "region {name} has {n} markers, want >= {min}");
    }
    let mut owner = vec![0; labels.len()];
    for idx in regions.values() {
        for &i in idx {
            owner[i] += 1;
        }
    }
    assert!(
        owner.iter().all(|&n| n == 1),
        "every marker is in exactly one region"
    );
    // The truth's resolved regions agree with the glob file.
    for (name, idx) in &regions {
        let names: Vec<&String> = idx.iter().map(|&i| &labels[i]).collect();
        let truth: Vec<&String> = s.truth.mixing.regions[name].iter().collect();
        assert_eq!(names, truth, "region {name}");
    }
}

#[test]
fn model_reconstructs_markers_up_to_the_sensor_noise() {
    let s = session(2);
    let mut all = Vec::new();
    for (take, truth) in s.takes.iter().zip(&s.truth.takes) {
        all.extend(residuals(&s.truth.mixing, take, truth));
    }
    let (mean, std) = mean_std(&all);
    assert!(mean.abs() < 0.01, "noise mean {mean}");
    assert!((std - NOISE_STD_MM).abs() < 0.01, "noise std {std}");
    // Without noise the model is exact (up to f32 storage).
    let synth = Synth::new(params(1)).expect("valid");
    let mut spec = synth.take_spec(0, "happy").expect("known emotion");
    spec.noise = false;
    let clean = synth.render_take(&spec).expect("renders");
    let r = residuals(&s.truth.mixing, &clean.take, &clean.truth);
    assert!(r.iter().all(|v| v.abs() < 1e-3));
}

#[test]
fn head_reference_markers_stay_rigid_while_the_face_moves() {
    let p = SynthParams {
        head_motion: true,
        ..params(1)
    };
    let s = generate_session(&p, Format::C3d).expect("valid");
    let take = &s.takes[0];
    let refs = s.regions.resolve(&take.labels).expect("resolves")["head_reference"].clone();
    let chin = take.marker_index("Chin").expect("chin exists");
    let spread = |i: usize, j: usize| {
        let d: Vec<f64> = (0..take.n_frames())
            .map(|f| dist(take.frame(f), i, j))
            .collect();
        let range =
            d.iter().cloned().fold(f64::MIN, f64::max) - d.iter().cloned().fold(f64::MAX, f64::min);
        (mean_std(&d).1, range)
    };
    for (a, &i) in refs.iter().enumerate() {
        for &j in &refs[a + 1..] {
            let (sd, _) = spread(i, j);
            assert!(sd < 0.4, "head reference distance varies by {sd} mm");
        }
        let (_, range) = spread(i, chin);
        assert!(
            range > 3.0,
            "the jaw moves only {range} mm relative to the head"
        );
    }
    // The head did move: the front marker travels more than the noise would.
    let front = take.marker_index("HeadFront").expect("exists");
    let ys: Vec<f64> = (0..take.n_frames())
        .map(|f| f64::from(take.frame(f)[front * 3 + 1]))
        .collect();
    assert!(mean_std(&ys).1 > 0.5, "head motion too small");
    // The facial sources never touch the head band.
    let m = &s.truth.mixing;
    for &i in &refs {
        for c in i * 3..i * 3 + 3 {
            for (k, src) in m.sources.iter().enumerate() {
                if src.role != "head" {
                    assert_eq!(m.matrix[c][k], 0.0, "{} moves {}", src.name, m.labels[i]);
                }
            }
        }
    }
}

#[test]
fn paired_takes_share_content_under_different_warps() {
    let s = session(3);
    let speech = s.truth.mixing.role_indices("speech");
    assert!(speech.len() >= 3);
    let brow = s.truth.mixing.role_indices("eyebrows");
    for sentence in ["s01", "s02", "s03"] {
        let takes: Vec<&TakeTruth> = s
            .truth
            .takes
            .iter()
            .filter(|t| t.sentence == sentence)
            .collect();
        assert_eq!(takes.len(), 3);
        let canonical = takes[0].warp[takes[0].warp.len() - 1];
        assert!(
            (2.0..=4.3).contains(&canonical),
            "sentence lasts {canonical} s"
        );
        let lengths: Vec<usize> = takes.iter().map(|t| t.n_frames()).collect();
        assert!(
            lengths[0] != lengths[1] || lengths[1] != lengths[2],
            "{lengths:?}"
        );
        for t in &takes {
            let scale = (t.n_frames() - 1) as f64 / t.rate_hz / canonical;
            assert!((0.8..=1.2).contains(&scale), "warp scale {scale}");
            assert!(
                t.warp.windows(2).all(|w| w[1] > w[0]),
                "warp must be monotonic"
            );
        }
        // Un-warp: at the same canonical times the content sources agree.
        let (a, b) = (takes[1], takes[2]);
        for (f, &tau) in a.warp.iter().enumerate() {
            let g = frac_frame(&b.warp, tau);
            for &k in speech.iter().chain(&brow) {
                let vb = lerp(&b.source(k), g);
                let va = a.sources[f][k];
                assert!(
                    (va - vb).abs() < 0.02,
                    "{sentence} source {k}: {va} vs {vb}"
                );
            }
        }
    }
}

fn frac_frame(warp: &[f64], tau: f64) -> f64 {
    let hi = warp.partition_point(|&v| v <= tau).clamp(1, warp.len() - 1);
    let lo = hi - 1;
    (lo as f64 + (tau - warp[lo]) / (warp[hi] - warp[lo])).clamp(0.0, (warp.len() - 1) as f64)
}

fn lerp(v: &[f64], x: f64) -> f64 {
    let i = (x.floor() as usize).min(v.len() - 2);
    v[i] + (x - i as f64) * (v[i + 1] - v[i])
}

#[test]
fn emotion_source_sits_at_each_emotions_level() {
    let s = session(4);
    let m = &s.truth.mixing;
    assert_eq!(m.level_of("neutral"), Some(0.0));
    assert_eq!(m.level_of("happy"), Some(1.0));
    assert_eq!(m.level_of("frustrated"), Some(-1.0));
    let e = m.source_index("emotion").expect("emotion source");
    for t in &s.truth.takes {
        let base = m.level_of(&t.emotion).expect("known");
        assert!((t.emotion_level - base).abs() <= 0.15 * base.abs() + 1e-12);
        let (mean, _) = mean_std(&t.source(e));
        assert!((mean - t.emotion_level).abs() < 0.1, "{}: {mean}", t.name);
    }
    // Intensity differs a little between sentences.
    let happy: Vec<f64> = s
        .truth
        .takes
        .iter()
        .filter(|t| t.emotion == "happy")
        .map(|t| t.emotion_level)
        .collect();
    assert!(happy.windows(2).any(|w| (w[0] - w[1]).abs() > 1e-3));
    // Its field reaches mouth corners, cheeks, brows and lids.
    for label in ["MouthCornerL", "CheekL6", "BrowL1", "LidLowerR"] {
        let i = m.labels.iter().position(|l| l == label).expect("label");
        let norm: f64 = (0..3)
            .map(|a| m.matrix[i * 3 + a][e].powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(norm > 0.5, "emotion moves {label} by only {norm} mm");
    }
}

#[test]
fn any_emotion_names_get_distinct_levels() {
    let p = SynthParams {
        emotions: vec!["sad".into(), "happy".into(), "angry".into()],
        ..params(1)
    };
    let synth = Synth::new(p).expect("valid");
    let levels: Vec<f64> = ["sad", "happy", "angry"]
        .iter()
        .map(|e| synth.level_of(e).expect("known"))
        .collect();
    assert_eq!(levels[1], 1.0);
    assert!(levels[0] != levels[2] && levels[0] != 1.0 && levels[2] != 1.0);
    assert!(matches!(
        synth.level_of("calm"),
        Err(SynthError::UnknownEmotion(_))
    ));
}

#[test]
fn blinks_are_short_events_that_close_the_upper_lids() {
    let s = session(8);
    let m = &s.truth.mixing;
    let lid = m
        .labels
        .iter()
        .position(|l| l == "LidUpperL")
        .expect("label");
    let seconds: f64 = s
        .truth
        .takes
        .iter()
        .map(|t| t.n_frames() as f64 / t.rate_hz)
        .sum();
    let count: usize = s.truth.takes.iter().map(|t| t.blinks.len()).sum();
    assert!(
        count as f64 >= seconds / 8.0,
        "{count} blinks in {seconds} s"
    );
    for (take, t) in s.takes.iter().zip(&s.truth.takes) {
        for b in &t.blinks {
            assert!((0.1..=0.25).contains(&b.duration_s));
            let peak = ((b.start_s + 0.4 * b.duration_s) * t.rate_hz).round() as usize;
            let drop = m.rest[lid * 3 + 1] - f64::from(take.frame(peak)[lid * 3 + 1]);
            assert!(drop > 5.0, "{}: lid drops only {drop} mm", t.name);
        }
    }
}

#[test]
fn counterpart_renders_another_emotion_at_the_same_timing() {
    let synth = Synth::new(params(2)).expect("valid");
    let a_spec = synth.take_spec(1, "frustrated").expect("valid");
    let b_own = synth.take_spec(1, "happy").expect("valid");
    let b_spec = b_own.clone().with_timing_of(&a_spec);
    assert_ne!(b_own.warp, a_spec.warp);
    let a = synth.render_take(&a_spec).expect("renders");
    let b = synth.render_take(&b_spec).expect("renders");
    assert_eq!(a.take.n_frames(), b.take.n_frames());
    assert_eq!(b.truth.emotion, "happy");
    let m = synth.mixing_truth();
    let e = m.source_index("emotion").expect("source");
    let shift = b.truth.emotion_level - a.truth.emotion_level;
    assert!(shift > 1.5);
    // Only the emotion differs: markers move by exactly its column times the level change.
    for f in 0..a.take.n_frames() {
        for (c, row) in m.matrix.iter().enumerate() {
            let diff = f64::from(b.take.frame(f)[c] - a.take.frame(f)[c]);
            assert!((diff - row[e] * shift).abs() < 1e-3);
        }
        for k in 0..m.sources.len() {
            let want = if k == e { shift } else { 0.0 };
            assert!((b.truth.sources[f][k] - a.truth.sources[f][k] - want).abs() < 1e-12);
        }
    }
    // A warp from another sentence is refused.
    let other = synth.take_spec(0, "happy").expect("valid");
    let wrong = b_own.with_timing_of(&other);
    assert!(matches!(
        synth.render_take(&wrong),
        Err(SynthError::WarpMismatch { .. })
    ));
}

#[test]
fn benchmark_sized_session_reaches_12000_frames() {
    let s = session(12);
    let frames: usize = s.takes.iter().map(Take::n_frames).sum();
    assert!(frames >= 12_000, "{frames} frames");
    assert_eq!(s.takes.len(), 36);
}

#[test]
fn bad_params_are_refused_with_the_bad_value() {
    let bad = [
        SynthParams {
            rate_hz: 0.0,
            ..params(1)
        },
        SynthParams {
            sentences: 0,
            ..params(1)
        },
        SynthParams {
            emotions: vec![],
            ..params(1)
        },
        SynthParams {
            emotions: vec!["happy".into(), "happy".into()],
            ..params(1)
        },
        SynthParams {
            emotions: vec!["a/b".into()],
            ..params(1)
        },
        SynthParams {
            emotions: vec!["".into()],
            ..params(1)
        },
    ];
    for p in bad {
        let err = Synth::new(p.clone()).expect_err("invalid params");
        assert!(!err.to_string().is_empty(), "{p:?}");
    }
    let err = Synth::new(SynthParams {
        emotions: vec!["a/b".into()],
        ..params(1)
    })
    .expect_err("bad name");
    assert!(err.to_string().contains("a/b"));
    // Sizes that would fill memory before a take is written are refused up front.
    for (p, needle) in [
        (
            SynthParams {
                rate_hz: 1e7,
                ..params(1)
            },
            "at most 2000 Hz, got 10000000",
        ),
        (
            SynthParams {
                sentences: 1_000_000,
                ..params(1)
            },
            "at most 10000 sentences",
        ),
    ] {
        let err = Synth::new(p).expect_err("too large");
        assert!(err.to_string().contains(needle), "{err}");
    }
}

#[test]
fn written_session_reads_back_with_its_truth() {
    let dir = tempfile::tempdir().expect("temp dir");
    let p = SynthParams {
        sentences: 1,
        emotions: vec!["neutral".into(), "happy".into()],
        ..params(1)
    };
    let summary = write_session(dir.path(), &p, Format::Trc).expect("writes");
    assert_eq!(summary.takes, vec!["s01_neutral", "s01_happy"]);
    let session = Session::load(&summary.manifest).expect("manifest loads");
    let truth = load_truth(dir.path()).expect("truth loads");
    let regions = Regions::load(&dir.path().join("regions.toml")).expect("regions load");
    assert_eq!(truth.takes.len(), 2);
    for (path, t) in session.take_paths().iter().zip(&truth.takes) {
        let take = replay::load(path).expect("take loads");
        assert_eq!(take.n_frames(), t.n_frames());
        regions.resolve(&take.labels).expect("regions resolve");
        let r = residuals(&truth.mixing, &take, t);
        let (_, std) = mean_std(&r);
        assert!(
            (std - NOISE_STD_MM).abs() < 0.02,
            "{} residual std {std}",
            t.name
        );
    }
}

#[test]
fn generated_manifests_round_trip_through_parse() {
    let s = session(1);
    let text = s.session.to_toml().expect("serialises");
    assert_eq!(Session::parse(&text).expect("parses"), s.session);
    let rtext = s.regions.to_toml().expect("serialises");
    assert_eq!(Regions::parse(&rtext).expect("parses"), s.regions);
}
