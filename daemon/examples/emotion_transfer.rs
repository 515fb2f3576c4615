//! The emotion edit's transfer error, variant x seed x ordered pair (issue 34): the tables of
//! `docs/emotion.md`, printed as Markdown. `scripts/emotion-table` builds and runs it.
//!
//! ```text
//! cargo run --example emotion_transfer -- --variants base,intensity --seeds 1,2,3
//! cargo run --example emotion_transfer -- --capture facial-sing --seeds 1,2,3,4,5
//! cargo run --example emotion_transfer -- --capture custom --files a.c3d,b.c3d \
//!     --head root-1,root-2,root-3 --regions r.toml --seeds 1 --name mine
//! ```
//!
//! Options: `--emoshift PATH` (default: the `emoshift` built beside this example), `--takes N`
//! source takes per emotion (default 3), `--work DIR` to keep the sessions (default: a
//! temporary folder); `--turn` turns each trained model's components by a random rotation
//! before the analysis (the same model split another way); `--axes components` analyses with
//! the emotion components as axes (the space before issue 34); for captures, `--field-mm`, `--jitter-s`, `--pace-spread` and
//! `--sentence-s` change the injection (defaults as `emoshift inject`).

use std::path::{Path, PathBuf};

use daemon::offline::inject::InjectParams;

#[path = "../tests/it/transfer.rs"]
mod transfer;

use transfer::{
    capture_session, pair_errors, prepare_capture, prepare_synth, variant, CaptureTruth, Emoshift,
    PairErrors, Prep, SynthTruth, VARIANTS,
};

struct Args {
    exe: Emoshift,
    variants: Vec<String>,
    capture: Option<String>,
    name: Option<String>,
    files: Vec<PathBuf>,
    head: Vec<String>,
    regions: Option<PathBuf>,
    seeds: Vec<u64>,
    takes: usize,
    work: Option<PathBuf>,
    inject: InjectParams,
    turn: bool,
    prep: Prep,
}

fn list(text: &str) -> Vec<String> {
    text.split(',').map(|s| s.trim().to_string()).collect()
}

fn parse() -> Result<Args, String> {
    let here = std::env::current_exe().map_err(|e| e.to_string())?;
    let beside = here
        .parent()
        .and_then(Path::parent)
        .map(|d| d.join("emoshift"))
        .ok_or("cannot find the build folder")?;
    let mut a = Args {
        exe: Emoshift(beside),
        variants: Vec::new(),
        capture: None,
        name: None,
        files: Vec::new(),
        head: Vec::new(),
        regions: None,
        seeds: vec![1, 2, 3],
        takes: 3,
        work: None,
        inject: InjectParams::default(),
        turn: false,
        prep: Prep::default(),
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        if flag == "--turn" {
            a.turn = true;
            continue;
        }
        let value = it.next().ok_or(format!("{flag} needs a value"))?;
        match flag.as_str() {
            "--emoshift" => a.exe = Emoshift(value.into()),
            "--variants" if value == "all-variants" => {
                a.variants = VARIANTS.iter().map(|v| v.to_string()).collect()
            }
            "--variants" => a.variants = list(&value),
            "--capture" => a.capture = Some(value),
            "--name" => a.name = Some(value),
            "--files" => a.files = list(&value).into_iter().map(PathBuf::from).collect(),
            "--head" => a.head = list(&value),
            "--regions" => a.regions = Some(value.into()),
            "--seeds" => {
                a.seeds = list(&value)
                    .iter()
                    .map(|s| s.parse().map_err(|_| format!("bad seed {s:?}")))
                    .collect::<Result<_, _>>()?
            }
            "--takes" => a.takes = value.parse().map_err(|_| "bad --takes")?,
            "--work" => a.work = Some(value.into()),
            "--axes" => a.prep.component_axes = value == "components",
            "--field-mm" | "--jitter-s" | "--pace-spread" | "--sentence-s" => {
                let v: f64 = value.parse().map_err(|_| format!("bad {flag}"))?;
                match flag.as_str() {
                    "--field-mm" => a.inject.field_mm = v,
                    "--jitter-s" => a.inject.jitter_s = v,
                    "--pace-spread" => a.inject.pace_spread = v,
                    _ => a.inject.sentence_s = v,
                }
            }
            _ => return Err(format!("unknown option {flag}")),
        }
    }
    if a.variants.is_empty() && a.capture.is_none() {
        return Err(format!(
            "give --variants (any of {}, or all-variants) or --capture (facial-sing, animface, custom)",
            VARIANTS.join(",")
        ));
    }
    Ok(a)
}

fn main() {
    let args = match parse() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("emotion_transfer: {e}");
            std::process::exit(2);
        }
    };
    let temp = tempfile::tempdir().expect("temp dir");
    let work = args
        .work
        .clone()
        .unwrap_or_else(|| temp.path().to_path_buf());
    println!("| session | seed | pair | mean | worst take | floor | takes |");
    println!("|---|---|---|---|---|---|---|");
    let mut summary = Vec::new();
    for name in &args.variants {
        for &seed in &args.seeds {
            let params = variant(name, seed).unwrap_or_else(|| panic!("unknown variant {name}"));
            let dir = work.join(format!("{name}-{seed}"));
            let prep = Prep {
                turn: args.turn.then_some(seed),
                ..args.prep.clone()
            };
            let model = prepare_synth(&args.exe, &dir, &params, &prep);
            let errors = pair_errors(
                &args.exe,
                &dir,
                &model,
                &SynthTruth::new(params),
                args.takes,
            );
            summary.push(report(name, seed, &errors));
        }
    }
    if let Some(capture) = &args.capture {
        let (files, head, regions) = capture_inputs(&args, capture);
        let capture = args.name.as_ref().unwrap_or(capture);
        let head: Vec<&str> = head.iter().map(String::as_str).collect();
        for &seed in &args.seeds {
            let params = InjectParams {
                seed,
                ..args.inject.clone()
            };
            let session = capture_session(&files, &head, &params);
            let dir = work.join(format!("{capture}-{seed}"));
            let model = prepare_capture(&args.exe, &dir, &session, &regions, &args.prep);
            let errors = pair_errors(&args.exe, &dir, &model, &CaptureTruth(session), args.takes);
            summary.push(report(capture, seed, &errors));
        }
    }
    println!();
    println!("| session | seed | worst pair mean | worst take |");
    println!("|---|---|---|---|");
    for line in summary {
        println!("{line}");
    }
}

/// The repository's fixtures for a named capture, or the files given.
fn capture_inputs(args: &Args, capture: &str) -> (Vec<PathBuf>, Vec<String>, PathBuf) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let fixtures = root.join("tests/fixtures");
    match capture {
        "facial-sing" => (
            vec![root.join("../replay/tests/fixtures/Facial-Sing.c3d")],
            (1..=6).map(|i| format!("root-{i}")).collect(),
            fixtures.join("facial-sing.regions.toml"),
        ),
        "animface" => (
            ["JawMoCap.c3d", "EyebrowsMoCap.c3d"]
                .iter()
                .map(|f| fixtures.join("animface").join(f))
                .collect(),
            list("ForeHead_M,ForeHead_L,ForeHead_R,NoseTop"),
            fixtures.join("animface.regions.toml"),
        ),
        _ => (
            args.files.clone(),
            args.head.clone(),
            args.regions
                .clone()
                .expect("--regions for a custom capture"),
        ),
    }
}

/// Prints one row per pair and returns the session's summary row.
fn report(name: &str, seed: u64, errors: &[PairErrors]) -> String {
    for e in errors {
        let takes: Vec<String> = e.takes.iter().map(|t| format!("{t:.3}")).collect();
        println!(
            "| {name} | {seed} | {}->{} | {:.3} | {:.3} | {:.3} | {} |",
            e.from,
            e.to,
            e.mean(),
            e.worst(),
            e.floor(),
            takes.join(" ")
        );
    }
    let worst_pair = errors.iter().map(PairErrors::mean).fold(0.0, f64::max);
    let worst_take = errors.iter().map(PairErrors::worst).fold(0.0, f64::max);
    eprintln!("{name} seed {seed}: worst pair {worst_pair:.3}, worst take {worst_take:.3}");
    format!("| {name} | {seed} | {worst_pair:.3} | {worst_take:.3} |")
}
