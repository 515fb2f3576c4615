//! Issue 12: defaults that hold on faces emoshift did not make. Real captures (Facial-Sing,
//! AnimFace) trained with no regions file and no flags, and synthetic faces of other layouts
//! (other marker sets, names, rigid markers or none, head motion or none), checked against
//! their truth.

use std::path::{Path, PathBuf};

use daemon::offline::training::{self, HeadChoice, PrepOptions, SpeedLimit};
use daemon::offline::{self, LoadedTake};
use ica_core::model::IcaModel;
use ica_core::quality::WarningKind;
use ica_core::stabilise::{to_world_into, Stabiliser};
use replay::synth::{generate_session, Layout, MarkerSet, Naming, RigidMarkers, SynthParams};

use crate::common::{corr, ok as emoshift, p as s, project_series};

fn fixture(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

fn facial_sing() -> PathBuf {
    fixture("../replay/tests/fixtures/Facial-Sing.c3d")
}

fn loaded(path: &Path) -> LoadedTake {
    LoadedTake {
        path: path.to_path_buf(),
        take: offline::load_take(path).expect("fixture loads"),
    }
}

fn defaults() -> PrepOptions {
    PrepOptions {
        rate_hz: None,
        max_missing_share: 0.5,
        speed: SpeedLimit::Auto,
        head: HeadChoice::auto(),
        bounds: true,
    }
}

fn roots() -> Vec<String> {
    (1..=6).map(|i| format!("root-{i}")).collect()
}

#[test]
fn issue12_facial_sing_reference_is_the_six_root_markers_by_default() {
    let data = training::prepare(&[loaded(&facial_sing())], &defaults()).expect("prepares");
    assert_eq!(data.reference, roots(), "{:?}", data.head);
    assert_eq!(data.head.source, "geometry");
    // The rig flexes beyond the capture's (filtered) noise: stabilised with a warning.
    assert_eq!(data.head.rigid, Some(false));
    let motion = data.head.motion_mm.expect("measured");
    assert!(motion > 20.0, "head motion {motion} mm");
}

/// Seeded uniform numbers (SplitMix64), so the injected signals are reproducible.
struct Uniform(u64);

impl Uniform {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A slow two-level signal: 0 and 1, switching every 3 to 6 s with a 0.25 s raised-cosine
/// transition, like an emotion changing between sentences.
fn two_level(frames: usize, rate_hz: f64, rng: &mut Uniform) -> Vec<f64> {
    let trans = (0.25 * rate_hz) as usize;
    let mut s = vec![0.0; frames];
    let (mut level, mut t) = (0.0, 0usize);
    while t < frames {
        let dwell = ((3.0 + 3.0 * rng.next()) * rate_hz) as usize;
        for v in s.iter_mut().skip(t).take(dwell) {
            *v = level;
        }
        t += dwell;
        let next = 1.0 - level;
        for k in 0..trans.min(frames.saturating_sub(t)) {
            let w = 0.5 * (1.0 - (std::f64::consts::PI * k as f64 / trans as f64).cos());
            s[t + k] = level + (next - level) * w;
        }
        t += trans;
        level = next;
    }
    s
}

/// Adds `amplitude_mm · s(t)` along a random direction to every face marker (all but
/// `head`), in head coordinates of the `head` markers, and returns the signal.
fn inject(take: &mut replay::Take, head: &[usize], amplitude_mm: f64, seed: u64) -> Vec<f64> {
    let mut rng = Uniform(seed);
    let dir: Vec<f64> = (0..3).map(|_| rng.next() - 0.5).collect();
    let norm = dir.iter().map(|v| v * v).sum::<f64>().sqrt();
    let signal = two_level(take.n_frames(), take.rate_hz, &mut rng);
    let n = take.n_markers();
    let mut st = Stabiliser::fit(&take.positions, &take.missing, n, head.to_vec()).expect("fit");
    let mut offset = vec![0.0f32; n * 3];
    let mut world = vec![0.0f32; n * 3];
    for (f, s) in signal.iter().enumerate() {
        for m in (0..n).filter(|m| !head.contains(m)) {
            for a in 0..3 {
                offset[m * 3 + a] = (amplitude_mm * s * dir[a] / norm) as f32;
            }
        }
        let est = st.estimate(take.frame(f), take.frame_missing(f));
        // The displacement is a vector: rotate it into the world, without the translation.
        let rotation_only = ica_core::stabilise::Pose {
            translation: nalgebra::Vector3::zeros(),
            ..est.pose
        };
        to_world_into(&rotation_only, &offset, &mut world);
        let frame = &mut take.positions[f * n * 3..(f + 1) * n * 3];
        for (i, (p, w)) in frame.iter_mut().zip(&world).enumerate() {
            if !take.missing[f * n + i / 3] {
                *p += w;
            }
        }
    }
    signal
}

/// Trains with default settings on `takes` and returns the best |r| of any component with the
/// concatenated `signals`.
fn best_recovery(dir: &Path, takes: &[PathBuf], signals: &[Vec<f64>]) -> f64 {
    let model = dir.join("model.json");
    let mut args = vec!["train", "--force", "--out", s(&model)];
    args.extend(takes.iter().map(|p| s(p)));
    let out = emoshift(&args);
    for line in out
        .lines()
        .filter(|l| l.starts_with("head ") || l.starts_with("components"))
    {
        eprintln!("  {line}");
    }
    let series = project_series(&model, takes);
    let truth: Vec<f64> = signals.concat();
    series
        .iter()
        .map(|c| corr(c, &truth).abs())
        .fold(0.0, f64::max)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[test]
fn issue12_a_slow_signal_injected_into_real_captures_is_recovered_with_defaults() {
    let dir = tempfile::tempdir().expect("temp dir");
    let original = offline::load_take(&facial_sing()).expect("take");
    let head: Vec<usize> = roots()
        .iter()
        .map(|l| original.marker_index(l).expect("root marker"))
        .collect();
    let mut facial = Vec::new();
    for seed in 1..=5 {
        let mut take = original.clone();
        let signal = inject(&mut take, &head, 2.5, seed);
        let path = dir.path().join(format!("sing{seed}.c3d"));
        replay::save(&path, &take).expect("write");
        facial.push(best_recovery(dir.path(), &[path], &[signal]));
    }
    eprintln!("Facial-Sing, injected 2.5 mm two-level signal, best |r| per seed: {facial:.2?}");
    // AnimFace has no rigid marker at all: its forehead and nose top carry the injection's
    // head frame, and the reference found is made of face markers that move with it.
    let names = ["ForeHead_M", "ForeHead_L", "ForeHead_R", "NoseTop"];
    let mut anim = Vec::new();
    for seed in 1..=3 {
        let (mut paths, mut signals) = (Vec::new(), Vec::new());
        for (k, file) in ["JawMoCap.c3d", "EyebrowsMoCap.c3d"].iter().enumerate() {
            let mut take = offline::load_take(&fixture(&format!("tests/fixtures/animface/{file}")))
                .expect("take");
            let idx: Vec<usize> = names
                .iter()
                .map(|l| take.marker_index(l).expect("marker"))
                .collect();
            signals.push(inject(&mut take, &idx, 2.5, seed * 10 + k as u64));
            let path = dir.path().join(format!("anim{seed}_{file}"));
            replay::save(&path, &take).expect("write");
            paths.push(path);
        }
        anim.push(best_recovery(dir.path(), &paths, &signals));
    }
    eprintln!("AnimFace jaw + eyebrows, best |r| per seed: {anim:.2?}");
    // Before issue 12 the automatic reference took face markers and the default model held
    // the signal at |r| 0.40 on Facial-Sing.
    assert!(median(facial.clone()) >= 0.80, "Facial-Sing {facial:?}");
    assert!(facial.iter().all(|&r| r >= 0.5), "Facial-Sing {facial:?}");
    // Lower on AnimFace: no marker there is rigid (its forehead follows the brows in the
    // eyebrow exercise), so the injection's own head frame is a part of the face, and the
    // range-of-motion exercises dominate a 40 s session.
    assert!(median(anim.clone()) >= 0.4, "AnimFace {anim:?}");
}

/// RMS (mm, 3-D) between `output` and `input` over the input's present samples that
/// preparation kept (not glitches, marker in the model), and over the face markers only.
fn amount_zero_error(
    input: &replay::Take,
    output: &replay::Take,
    data: &training::PreparedData,
) -> f64 {
    let n = data.labels.len();
    let (mut sq, mut count) = (0.0, 0usize);
    for f in 0..input.n_frames() {
        for (m, label) in input.labels.iter().enumerate() {
            let Some(model_m) = data.labels.iter().position(|l| l == label) else {
                continue;
            };
            if label.starts_with("root") || data.missing[(f * n + model_m) * 3] {
                continue;
            }
            let (Some(a), Some(b)) = (input.sample(f, m), output.sample(f, m)) else {
                continue;
            };
            sq += (0..3).map(|k| f64::from(a[k] - b[k]).powi(2)).sum::<f64>();
            count += 1;
        }
    }
    (sq / count.max(1) as f64).sqrt()
}

#[test]
fn issue12_facial_sing_with_defaults_reproduces_its_face_and_fills_its_gaps() {
    let dir = tempfile::tempdir().expect("temp dir");
    let model = dir.path().join("model.json");
    emoshift(&["train", s(&facial_sing()), "--out", s(&model)]);
    let edited = dir.path().join("edited.c3d");
    emoshift(&[
        "edit",
        "--model",
        s(&model),
        s(&facial_sing()),
        "--out",
        s(&edited),
    ]);
    let input = offline::load_take(&facial_sing()).expect("input");
    let output = offline::load_take(&edited).expect("output");
    let data = training::prepare(&[loaded(&facial_sing())], &defaults()).expect("prepares");
    let err = amount_zero_error(&input, &output, &data);
    // Hidden samples (a 0.5 s block of two markers, every 7th frame of three more) filled by
    // the default model, against the hidden truth.
    let mut holey = input.clone();
    let n = input.n_markers();
    let mut hidden = Vec::new();
    let hide = [
        "section10-2",
        "section13-2",
        "section1-1",
        "section8-1",
        "section11-1",
    ];
    for (i, label) in hide.iter().enumerate() {
        let m = input.marker_index(label).expect("marker");
        for f in 0..input.n_frames() {
            let block = i < 2 && (400..450).contains(&f);
            if (block || (i >= 2 && f % 7 == i)) && !input.is_missing(f, m) {
                holey.missing[f * n + m] = true;
                hidden.push((f, m));
            }
        }
    }
    let holey_path = dir.path().join("holey.c3d");
    replay::save(&holey_path, &holey).expect("write");
    let filled_path = dir.path().join("filled.c3d");
    emoshift(&[
        "edit",
        "--model",
        s(&model),
        s(&holey_path),
        "--out",
        s(&filled_path),
    ]);
    let filled = offline::load_take(&filled_path).expect("filled");
    let fill = (hidden
        .iter()
        .map(|&(f, m)| {
            let (p, t) = (
                filled.sample(f, m).expect("filled"),
                input.sample(f, m).expect("truth"),
            );
            (0..3).map(|k| f64::from(p[k] - t[k]).powi(2)).sum::<f64>()
        })
        .sum::<f64>()
        / hidden.len() as f64)
        .sqrt();
    eprintln!("Facial-Sing defaults: amount-0 error {err:.2} mm on visible face samples, fill {fill:.2} mm");
    assert!(err <= 1.5, "amount-0 error {err:.2} mm");
    assert!(fill <= 2.5, "fill error {fill:.2} mm");
}

#[test]
fn issue12_too_many_components_on_a_small_session_warn_of_noise_and_instability() {
    // The issue's "other generator" face trained as its report did, `--components 10` on a
    // small session: three of the ten sit at the noise floor and restarts disagree.
    let dir = tempfile::tempdir().expect("temp dir");
    let params = SynthParams {
        seed: 5,
        sentences: 2,
        layout: Layout {
            naming: Naming::Snake,
            rigid: RigidMarkers::None,
            ..Layout::default()
        },
        ..SynthParams::default()
    };
    let session = generate_session(&params, replay::Format::C3d).expect("session");
    let mut args: Vec<String> = vec!["train".into(), "--components".into(), "10".into()];
    for (take, entry) in session.takes.iter().zip(&session.session.takes) {
        let path = dir.path().join(&entry.file);
        replay::save(&path, take).expect("write");
        args.push(s(&path).to_string());
    }
    let model = dir.path().join("m.json");
    args.extend(["--out".to_string(), s(&model).to_string()]);
    let argv: Vec<&str> = args.iter().map(String::as_str).collect();
    let out = emoshift(&argv);
    let m = IcaModel::load(std::fs::File::open(&model).expect("model")).expect("valid");
    assert!(m.quality().has(WarningKind::KeepsNoise), "{out}");
    assert!(m.quality().has(WarningKind::UnstableComponent), "{out}");
    // Named as components (c3), not as a bare number that reads as a count, and never at the
    // bound they are below.
    let unstable = out
        .lines()
        .find(|l| l.contains("not found again"))
        .expect("the warning");
    let (listed, advice) = unstable
        .split("below 0.9): ")
        .nth(1)
        .and_then(|l| l.split_once("; "))
        .expect("a list, then what to try");
    // Issue 37: what to try, with numbers.
    assert!(
        advice.contains("fewer components (--components ")
            && advice.contains("more frames")
            && advice.contains("more restarts (--restarts "),
        "{unstable}"
    );
    for item in listed.split(", ") {
        let (name, value) = item.split_once(" (").expect("c<k> (<corr>)");
        assert!(
            name.starts_with('c') && name[1..].parse::<usize>().is_ok(),
            "{item}"
        );
        let v: f64 = value.trim_end_matches(')').parse().expect("a number");
        assert!(v < 0.9, "{item}");
    }
    assert!(out.contains("at the noise floor"), "{out}");
}

#[test]
fn issue12_a_ten_frame_take_trains_with_a_warning() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut take = offline::load_take(&facial_sing()).expect("take");
    take.positions.truncate(10 * take.n_markers() * 3);
    take.missing.truncate(10 * take.n_markers());
    let path = dir.path().join("ten.c3d");
    replay::save(&path, &take).expect("write");
    let model = dir.path().join("m.json");
    let out = emoshift(&["train", s(&path), "--out", s(&model)]);
    assert!(out.contains("trained on 10 frames"), "{out}");
    let m = IcaModel::load(std::fs::File::open(&model).expect("model")).expect("valid");
    assert!(m.quality().has(WarningKind::FewFrames));
    let shown = emoshift(&["inspect", s(&model)]);
    assert!(shown.contains("trained on 10 frames"), "{shown}");
}

/// One synthetic layout: how it is rendered and what the head decision must be.
struct Case {
    name: &'static str,
    layout: Layout,
    head_motion: bool,
    stabilised: bool,
    /// Least best-match |r| of a component with the blink source.
    min_blink: f64,
}

fn cases() -> Vec<Case> {
    vec![
        // The issue's "other generator": 105 markers, names that are not ours, no rigid
        // marker, no head motion, a forehead that rises with the brows.
        Case {
            name: "snake names, no rigid markers, still head",
            layout: Layout {
                naming: Naming::Snake,
                rigid: RigidMarkers::None,
                ..Layout::default()
            },
            head_motion: false,
            stabilised: false,
            min_blink: 0.95,
        },
        Case {
            name: "sparse, numbered, Vicon band, moving head, jittered",
            layout: Layout {
                markers: MarkerSet::Sparse,
                naming: Naming::Numbered,
                rigid: RigidMarkers::Vicon,
                placement_jitter_mm: 3.0,
            },
            head_motion: true,
            stabilised: true,
            min_blink: 0.95,
        },
        // The hard case: the head moves and nothing is rigid. Stabilising on the
        // least-deforming markers (upper forehead, nose, upper cheeks) moves the whole face
        // with their own deformation; the model says so, and blinks come out mixed with it.
        Case {
            name: "no rigid markers, moving head, jittered",
            layout: Layout {
                rigid: RigidMarkers::None,
                placement_jitter_mm: 2.0,
                ..Layout::default()
            },
            head_motion: true,
            stabilised: true,
            min_blink: 0.5,
        },
    ]
}

#[test]
fn issue12_other_layouts_get_the_right_head_decision_and_their_sources_back() {
    let dir = tempfile::tempdir().expect("temp dir");
    for case in cases() {
        let mut blinks = Vec::new();
        let mut emotions = Vec::new();
        for seed in 1..=5 {
            // 4 sentences in 3 emotions: about 40 s, a dozen blinks.
            let params = SynthParams {
                seed,
                sentences: 4,
                head_motion: case.head_motion,
                layout: case.layout.clone(),
                ..SynthParams::default()
            };
            let session = generate_session(&params, replay::Format::C3d).expect("session");
            let mut paths = Vec::new();
            for (take, entry) in session.takes.iter().zip(&session.session.takes) {
                let path = dir.path().join(&entry.file);
                replay::save(&path, take).expect("write");
                paths.push(path);
            }
            // The head decision, as `train` makes it with defaults.
            let takes: Vec<LoadedTake> = paths.iter().map(|p| loaded(p)).collect();
            let data = training::prepare(&takes, &defaults()).expect("prepares");
            let label = format!("{} seed {seed}", case.name);
            assert_eq!(
                data.head.stabilised, case.stabilised,
                "{label}: {:?}",
                data.head
            );
            // Rigid as reported iff the truth moves none of the reference markers with the face
            // (by more than 0.1 mm per unit of a source: the fields' far tails are not motion).
            if case.stabilised {
                let truth = &session.truth.mixing;
                let moves = |label: &String| {
                    let m = truth.labels.iter().position(|l| l == label).expect("label");
                    (0..3).any(|a| {
                        truth.matrix[m * 3 + a]
                            .iter()
                            .zip(&truth.sources)
                            .any(|(v, src)| src.role != "head" && v.abs() > 0.1)
                    })
                };
                let truly_rigid = !data.reference.iter().any(moves);
                assert_eq!(
                    data.head.rigid,
                    Some(truly_rigid),
                    "{label}: {:?}",
                    data.head
                );
            }
            let moving: Vec<&String> = ["mouth", "jaw", "eyelids", "eyebrows"]
                .iter()
                .filter_map(|r| session.truth.mixing.regions.get(*r))
                .flatten()
                .collect();
            assert!(
                data.reference.iter().all(|l| !moving.contains(&l)),
                "{label}: reference {:?} holds a moving face marker",
                data.reference
            );
            // The sources come back as components, with default settings.
            let model = dir.path().join("model.json");
            let mut args = vec!["train", "--force", "--out", s(&model)];
            args.extend(paths.iter().map(|p| s(p)));
            emoshift(&args);
            let series = project_series(&model, &paths);
            let truth = &session.truth;
            let source = |name: &str| -> Vec<f64> {
                let k = truth
                    .mixing
                    .sources
                    .iter()
                    .position(|s| s.name == name)
                    .expect("source");
                truth.takes.iter().flat_map(|t| t.source(k)).collect()
            };
            let best = |truth: &[f64]| {
                series
                    .iter()
                    .map(|c| corr(c, truth).abs())
                    .fold(0.0, f64::max)
            };
            blinks.push(best(&source("blink")));
            emotions.push(best(&source("emotion")));
        }
        eprintln!(
            "{}: best |r| blink {blinks:.3?}, emotion {emotions:.3?}",
            case.name
        );
        assert!(
            blinks.iter().all(|&r| r > case.min_blink),
            "{}: blink {blinks:?}",
            case.name
        );
        assert!(
            emotions.iter().all(|&r| r > 0.9),
            "{}: emotion {emotions:?}",
            case.name
        );
    }
}
