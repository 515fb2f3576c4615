//! How many sentences per emotion a calibration session needs (issue 33): for each count N,
//! variant and seed, a synthetic session of N sentences in neutral, happy, sad and angry is
//! written, trained and analysed with default settings by the `emoshift` binary, and scored:
//! the emotion edit's transfer error (mean over ordered pairs of emotions, as
//! `docs/emotion.md` measures it) and the roles found (the share of the roles the generator
//! builds in: speech, eyebrows, eyelids, and an emotion space of its 2 directions, that the
//! analysis labels). A session whose analysis finds no emotion space scores error 1 (no
//! edit can be made: the whole displacement is missed). Prints CSV: `variant,seed,sentences,transfer_error,roles_found`.
//! `scripts/sentence-curve` runs it and draws `docs/session-curve.svg`.
//!
//! ```text
//! cargo run --release --example sentence_curve -- --counts 2,4,8 --variants base --seeds 1
//! ```

use std::path::Path;

use ica_core::model::{IcaModel, Role};

#[path = "../tests/it/transfer.rs"]
mod transfer;

use transfer::{pair_errors, prepare_synth, variant, Emoshift, Prep, SynthTruth};

fn list<T: std::str::FromStr>(text: &str) -> Vec<T> {
    text.split(',')
        .filter_map(|s| s.trim().parse().ok())
        .collect()
}

fn load(model: &Path) -> IcaModel {
    let file = std::fs::File::open(model).expect("the model");
    IcaModel::load(std::io::BufReader::new(file)).expect("a model")
}

/// The share of the four built-in roles the model's analysis labels.
fn roles_found(m: &IcaModel) -> f64 {
    let has = |r: Role| m.roles().contains(&r);
    let found = [
        has(Role::Speech),
        has(Role::Eyebrows),
        has(Role::Eyelids),
        has(Role::Emotion) && m.emotion().dims() == 2,
    ];
    found.iter().filter(|&&f| f).count() as f64 / found.len() as f64
}

fn main() {
    let mut counts: Vec<usize> = vec![2, 3, 4, 6, 8, 12];
    let mut variants: Vec<String> = vec!["base".into(), "intensity".into(), "all".into()];
    let mut seeds: Vec<u64> = vec![1, 2, 3];
    let mut it = std::env::args().skip(1);
    while let (Some(flag), Some(value)) = (it.next(), it.next()) {
        match flag.as_str() {
            "--counts" => counts = list(&value),
            "--variants" => variants = list(&value),
            "--seeds" => seeds = list(&value),
            other => panic!("unknown option {other} (--counts, --variants, --seeds)"),
        }
    }
    let here = std::env::current_exe().expect("this program");
    let exe = Emoshift(
        here.parent()
            .and_then(Path::parent)
            .map(|d| d.join("emoshift"))
            .expect("the build folder"),
    );
    let work = tempfile::tempdir().expect("temp dir");
    println!("variant,seed,sentences,transfer_error,roles_found");
    for name in &variants {
        for &seed in &seeds {
            for &n in &counts {
                let mut params = variant(name, seed).expect("a known variant");
                params.sentences = n;
                if let Err(e) = params.validate() {
                    // `all` records angry in 3 sentences only: fewer sentences cannot hold it.
                    eprintln!("sentence_curve: {name} with {n} sentences left out: {e}");
                    continue;
                }
                let dir = work.path().join(format!("{name}-{seed}-{n}"));
                let model = prepare_synth(&exe, &dir, &params, &Prep::default());
                let m = load(&model);
                // No emotion space found: no edit can be made, which leaves the whole
                // displacement as the error (1).
                let mean = match m.emotion().space_components().is_empty() {
                    true => 1.0,
                    false => {
                        let errors = pair_errors(&exe, &dir, &model, &SynthTruth::new(params), 2);
                        errors.iter().map(|e| e.mean()).sum::<f64>() / errors.len() as f64
                    }
                };
                println!("{name},{seed},{n},{mean:.4},{:.2}", roles_found(&m));
                std::fs::remove_dir_all(&dir).expect("clean up");
            }
        }
    }
}
