//! The emotion edit scored against a known truth (issues 13 and 34), shared by the tests and
//! `examples/emotion_transfer.rs` (which `scripts/emotion-table` runs for the full tables).
//!
//! A session with truth is written, trained and analysed with default settings through the
//! `emoshift` binary, as a user would. Then, for every ordered pair of emotions (A, B) and a
//! few takes of A, `emoshift edit --to-emotion B --amount 1` against the same edit at amount 0
//! is compared with the truth: the same take in B ([`TruthSource::counterfactual`]). The
//! transfer error of a take is `RMS(moved − zero − (truth − original)) / RMS(truth −
//! original)` over the samples the take has.
//!
//! The session variants of issue 34 are named in [`variant`].

#![allow(dead_code)] // each user takes a different part

use std::path::{Path, PathBuf};
use std::process::Command;

use daemon::offline::inject::{self, InjectParams, InjectedSession};
use replay::synth::{Layout, MarkerSet, Naming, RigidMarkers, Synth, SynthParams, Variation};
use replay::Take;

/// The `emoshift` binary.
#[derive(Debug, Clone)]
pub struct Emoshift(pub PathBuf);

impl Emoshift {
    /// Runs it; panics with its stderr when it fails.
    pub fn ok(&self, args: &[&str]) -> String {
        let out = Command::new(&self.0)
            .args(args)
            .output()
            .expect("emoshift runs");
        assert!(
            out.status.success(),
            "emoshift {args:?} failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).into_owned()
    }
}

fn s(path: &Path) -> &str {
    path.to_str().expect("utf-8 path")
}

/// A session whose edits have a known answer.
pub trait TruthSource {
    /// The emotions, in session order.
    fn emotions(&self) -> Vec<String>;
    /// Up to `count` takes of `emotion` to edit (ids for the two methods below).
    fn sources(&self, emotion: &str, count: usize) -> Vec<usize>;
    /// The take as the session has it.
    fn original(&self, id: usize) -> Take;
    /// The same take in `target`: what the edit should produce.
    fn counterfactual(&self, id: usize, target: &str) -> Take;
    /// The best a level edit can do without knowing the target take: the take at the levels
    /// of the target emotion's average take (`None` when that is the counterfactual itself).
    fn oracle(&self, _id: usize, _target: &str) -> Option<Take> {
        None
    }
}

/// A synthetic session: takes are (sentence, emotion) of the generator.
pub struct SynthTruth {
    /// The generator.
    pub synth: Synth,
    takes: Vec<(usize, String)>,
}

impl SynthTruth {
    /// The truth of the session `params` makes.
    pub fn new(params: SynthParams) -> SynthTruth {
        let synth = Synth::new(params).expect("valid parameters");
        let takes = synth
            .takes()
            .into_iter()
            .map(|(s, e)| (s, e.to_string()))
            .collect();
        SynthTruth { synth, takes }
    }
}

impl TruthSource for SynthTruth {
    fn emotions(&self) -> Vec<String> {
        self.synth.params().emotions.clone()
    }

    fn sources(&self, emotion: &str, count: usize) -> Vec<usize> {
        (0..self.takes.len())
            .filter(|&i| self.takes[i].1 == emotion)
            .take(count)
            .collect()
    }

    fn original(&self, id: usize) -> Take {
        let (sentence, emotion) = &self.takes[id];
        let spec = self.synth.take_spec(*sentence, emotion).expect("spec");
        self.synth.render_take(&spec).expect("render").take
    }

    fn counterfactual(&self, id: usize, target: &str) -> Take {
        let (sentence, emotion) = &self.takes[id];
        let spec = self.synth.take_spec(*sentence, emotion).expect("spec");
        let truth = self.synth.counterfactual(&spec, target).expect("spec");
        self.synth.render_take(&truth).expect("render").take
    }

    fn oracle(&self, id: usize, target: &str) -> Option<Take> {
        let (sentence, emotion) = &self.takes[id];
        let spec = self.synth.take_spec(*sentence, emotion).expect("spec");
        let levels = self.synth.mean_levels(target).expect("known emotion");
        Some(
            self.synth
                .render_take(&spec.with_levels(levels))
                .expect("render")
                .take,
        )
    }
}

/// A real-capture session with an injected field: takes are its cuts.
pub struct CaptureTruth(pub InjectedSession);

impl TruthSource for CaptureTruth {
    fn emotions(&self) -> Vec<String> {
        self.0.level_names()
    }

    fn sources(&self, emotion: &str, count: usize) -> Vec<usize> {
        let cuts = self.0.cuts();
        (0..cuts.len())
            .filter(|&i| cuts[i].emotion == emotion)
            .take(count)
            .collect()
    }

    fn original(&self, id: usize) -> Take {
        let cut = &self.0.cuts()[id];
        self.0.render(cut, cut.level)
    }

    fn counterfactual(&self, id: usize, target: &str) -> Take {
        let level = self.0.level_of(target).expect("a level of the session");
        self.0.render(&self.0.cuts()[id], level)
    }
}

/// The issue 34 variants (and `base`, the team's own 4 emotions over 2 directions), each a
/// session of 8 sentences in neutral, happy, sad and angry. `intensity`, `spread` and
/// `interaction` take another strength as `spread=2`. `None` for an unknown name.
pub fn variant(spec: &str, seed: u64) -> Option<SynthParams> {
    let (name, strength) = match spec.split_once('=') {
        Some((n, v)) => (n, Some(v.parse::<f64>().ok()?)),
        None => (spec, None),
    };
    let nv = |text: &str| text.parse().expect("a valid name=value");
    let mut p = SynthParams {
        seed,
        sentences: 8,
        emotions: ["neutral", "happy", "sad", "angry"]
            .iter()
            .map(|e| e.to_string())
            .collect(),
        emotion_dims: 2,
        ..SynthParams::default()
    };
    let v = &mut p.variation;
    match name {
        "base" => {}
        "intensity" => v.take_intensity = strength.unwrap_or(0.4),
        "spread" => v.spread_effects = strength.unwrap_or(1.0),
        "unequal" => v.takes = vec![nv("angry=3"), nv("happy=5")],
        "interaction" => v.interaction = strength.unwrap_or(0.03),
        "rate" => v.speech_rate = vec![nv("angry=1.2"), nv("sad=0.85")],
        "layout" => {
            p.head_motion = true;
            p.layout = Layout {
                markers: MarkerSet::Sparse,
                naming: Naming::Numbered,
                rigid: RigidMarkers::None,
                placement_jitter_mm: 2.0,
            };
        }
        "all" => {
            *v = Variation {
                take_intensity: 0.3,
                spread_effects: 1.0,
                takes: vec![nv("angry=3")],
                interaction: 0.05,
                speech_rate: vec![nv("angry=1.15")],
            };
            p.head_motion = true;
            p.layout.naming = Naming::Snake;
        }
        _ => return None,
    }
    Some(p)
}

/// Every variant name [`variant`] knows, `base` first.
pub const VARIANTS: [&str; 8] = [
    "base",
    "intensity",
    "spread",
    "unequal",
    "interaction",
    "rate",
    "layout",
    "all",
];

/// How a session is trained and analysed beyond the defaults.
#[derive(Debug, Clone, Default)]
pub struct Prep {
    /// Turn the trained model's components by a random rotation from this seed before the
    /// analysis ([`turn_model`]): the same model, split another way.
    pub turn: Option<u64>,
    /// `analyze --axes components`: the emotion components as the space's axes (the space
    /// before issue 34), for comparison.
    pub component_axes: bool,
}

/// Writes the synthetic session of `params` into `dir`, trains and analyses it with default
/// settings (and `prep`); returns the model's path.
pub fn prepare_synth(exe: &Emoshift, dir: &Path, params: &SynthParams, prep: &Prep) -> PathBuf {
    replay::synth::write_session(dir, params, replay::Format::C3d).expect("session");
    train_and_analyze(exe, dir, prep)
}

/// Turns the components of the model file at `path` by a random rotation `R` (seeded):
/// `mixing · Rᵀ`, `R · unmixing`. Every frame's components turn by `R`; the markers the model
/// reconstructs stay the same.
pub fn turn_model(path: &Path, seed: u64) {
    let text = std::fs::read_to_string(path).expect("model file");
    let mut v: serde_json::Value = serde_json::from_str(&text).expect("json");
    let rows = |v: &serde_json::Value| -> Vec<Vec<f64>> {
        v.as_array()
            .expect("rows")
            .iter()
            .map(|r| {
                r.as_array()
                    .expect("row")
                    .iter()
                    .map(|x| x.as_f64().expect("number"))
                    .collect()
            })
            .collect()
    };
    let mixing = nalgebra::DMatrix::from_row_iterator(
        rows(&v["mixing"]).len(),
        rows(&v["mixing"])[0].len(),
        rows(&v["mixing"]).into_iter().flatten(),
    );
    let unmixing = nalgebra::DMatrix::from_row_iterator(
        rows(&v["unmixing"]).len(),
        rows(&v["unmixing"])[0].len(),
        rows(&v["unmixing"]).into_iter().flatten(),
    );
    let m = unmixing.nrows();
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let random = nalgebra::DMatrix::from_fn(m, m, |_, _| {
        // xorshift64*: any full-rank matrix will do, its QR factor is a rotation.
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        (state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    });
    let r = random.qr().q();
    let to_json = |x: &nalgebra::DMatrix<f64>| {
        serde_json::Value::Array(
            (0..x.nrows())
                .map(|i| serde_json::json!(x.row(i).iter().copied().collect::<Vec<f64>>()))
                .collect(),
        )
    };
    v["mixing"] = to_json(&(mixing * r.transpose()));
    v["unmixing"] = to_json(&(&r * unmixing));
    std::fs::write(path, serde_json::to_string(&v).expect("json")).expect("model written");
}

/// Writes the injected session into `dir` with the `regions` file beside its manifest (as
/// `emoshift inject --regions` does), trains and analyses it with default settings; returns
/// the model's path.
pub fn prepare_capture(
    exe: &Emoshift,
    dir: &Path,
    session: &InjectedSession,
    regions: &Path,
    prep: &Prep,
) -> PathBuf {
    inject::write_session(dir, session, replay::Format::C3d).expect("session");
    std::fs::copy(regions, dir.join("regions.toml")).expect("regions copied");
    train_and_analyze(exe, dir, prep)
}

fn train_and_analyze(exe: &Emoshift, dir: &Path, prep: &Prep) -> PathBuf {
    let model = dir.join("model.json");
    train(exe, dir, &model);
    if let Some(seed) = prep.turn {
        turn_model(&model, seed);
    }
    analyze(exe, dir, &model, prep.component_axes);
    model
}

/// `emoshift train` with default settings on the session in `dir`, into `model`.
pub fn train(exe: &Emoshift, dir: &Path, model: &Path) {
    let manifest = dir.join("session.toml");
    exe.ok(&["train", "--manifest", s(&manifest), "--out", s(model)]);
}

/// `emoshift analyze --write-model` of `model` on the session in `dir` (with the emotion
/// components as axes when `component_axes`).
pub fn analyze(exe: &Emoshift, dir: &Path, model: &Path, component_axes: bool) {
    let manifest = dir.join("session.toml");
    let stem = model
        .file_stem()
        .and_then(|s| s.to_str())
        .expect("a model file name");
    let report = dir.join(format!("{stem}-report"));
    let axes = if component_axes {
        "components"
    } else {
        "fitted"
    };
    exe.ok(&[
        "analyze",
        "--model",
        s(model),
        "--manifest",
        s(&manifest),
        "--out",
        s(&report),
        "--write-model",
        "--axes",
        axes,
        "--force",
    ]);
}

/// A session cut from `captures` (files with the same markers) with `params`, the field in
/// the frame of `head`.
pub fn capture_session(
    captures: &[PathBuf],
    head: &[&str],
    params: &InjectParams,
) -> InjectedSession {
    let takes = captures
        .iter()
        .map(|p| {
            let take = daemon::offline::load_take(p).expect("capture loads");
            (p.display().to_string(), take)
        })
        .collect();
    let head: Vec<String> = head.iter().map(|h| h.to_string()).collect();
    InjectedSession::build(takes, &head, params).expect("session")
}

/// The transfer errors of one ordered pair of emotions.
#[derive(Debug, Clone)]
pub struct PairErrors {
    /// Source emotion.
    pub from: String,
    /// Target emotion.
    pub to: String,
    /// Error of each take edited.
    pub takes: Vec<f64>,
    /// Error of the oracle on each take (empty when the truth is known exactly).
    pub floor: Vec<f64>,
}

impl PairErrors {
    /// Mean over the takes.
    pub fn mean(&self) -> f64 {
        self.takes.iter().sum::<f64>() / self.takes.len().max(1) as f64
    }

    /// The worst take.
    pub fn worst(&self) -> f64 {
        self.takes.iter().copied().fold(0.0, f64::max)
    }

    /// The oracle's mean over the takes (0 when the truth is known exactly).
    pub fn floor(&self) -> f64 {
        self.floor.iter().sum::<f64>() / self.floor.len().max(1) as f64
    }
}

/// Edits `per_emotion` takes of every emotion to every other one with `model` and scores them.
pub fn pair_errors(
    exe: &Emoshift,
    dir: &Path,
    model: &Path,
    truth: &dyn TruthSource,
    per_emotion: usize,
) -> Vec<PairErrors> {
    let emotions = truth.emotions();
    let mut out = Vec::new();
    for a in &emotions {
        let sources = truth.sources(a, per_emotion);
        let mut zeros = Vec::new();
        for &id in &sources {
            let original = truth.original(id);
            let input = dir.join(format!("edit-{id}.c3d"));
            replay::save(&input, &original).expect("write");
            let zero = edit(
                exe,
                model,
                &input,
                emotions.iter().find(|e| *e != a).expect("two emotions"),
                "0",
            );
            zeros.push((original, input, zero));
        }
        for b in emotions.iter().filter(|b| *b != a) {
            let (mut takes, mut floor) = (Vec::new(), Vec::new());
            for (&id, (original, input, zero)) in sources.iter().zip(&zeros) {
                let moved = edit(exe, model, input, b, "1");
                let counterfactual = truth.counterfactual(id, b);
                takes.push(transfer_error(original, zero, &moved, &counterfactual));
                if let Some(best) = truth.oracle(id, b) {
                    floor.push(transfer_error(original, original, &best, &counterfactual));
                }
            }
            out.push(PairErrors {
                from: a.clone(),
                to: b.clone(),
                takes,
                floor,
            });
        }
    }
    out
}

fn edit(exe: &Emoshift, model: &Path, input: &Path, target: &str, amount: &str) -> Take {
    let out = input.with_extension(format!("{target}-{amount}.c3d"));
    exe.ok(&[
        "edit",
        "--model",
        s(model),
        s(input),
        "--out",
        s(&out),
        "--to-emotion",
        target,
        "--amount",
        amount,
        "--force",
    ]);
    replay::load(&out).expect("edited take")
}

/// `RMS(moved − zero − (truth − original)) / RMS(truth − original)` over the samples
/// `original` has (gaps are filled by the edit but have no truth). The edits may order the
/// markers otherwise (the model's first): they are matched by label.
pub fn transfer_error(original: &Take, zero: &Take, moved: &Take, truth: &Take) -> f64 {
    let n = original.n_markers();
    let at: Vec<usize> = original
        .labels
        .iter()
        .map(|l| moved.marker_index(l).expect("the edit keeps every marker"))
        .collect();
    let (mut miss, mut shift) = (0.0, 0.0);
    for f in 0..original.n_frames() {
        for m in (0..n).filter(|&m| !original.is_missing(f, m)) {
            for a in 0..3 {
                let i = (f * n + m) * 3 + a;
                let j = (f * n + at[m]) * 3 + a;
                let d = f64::from(truth.positions[i]) - f64::from(original.positions[i]);
                let e = f64::from(moved.positions[j]) - f64::from(zero.positions[j]);
                miss += (e - d).powi(2);
                shift += d * d;
            }
        }
    }
    (miss / shift.max(1e-300)).sqrt()
}

/// Prints `errors` under `label` and fails unless every pair's mean is within `pair` and
/// every take within `take`, after checking that every ordered pair of `emotions` is there.
pub fn assert_within(label: &str, errors: &[PairErrors], emotions: usize, pair: f64, take: f64) {
    eprintln!("{label}: {}", describe(errors));
    assert_eq!(
        errors.len(),
        emotions * (emotions - 1),
        "{label}: every ordered pair"
    );
    for e in errors {
        assert!(
            e.mean() <= pair && e.worst() <= take,
            "{label}: {}->{} mean {:.3}, worst take {:.3}",
            e.from,
            e.to,
            e.mean(),
            e.worst()
        );
    }
}

/// One line per pair: `a->b mean (worst)`.
pub fn describe(errors: &[PairErrors]) -> String {
    errors
        .iter()
        .map(|e| format!("{}->{} {:.3} ({:.3})", e.from, e.to, e.mean(), e.worst()))
        .collect::<Vec<_>>()
        .join(", ")
}
