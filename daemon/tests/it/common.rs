//! Helpers shared by the CLI-level test files: run the `emoshift` binary as a user would.

use std::path::Path;
use std::process::{Command, Output};

/// Runs `emoshift` with `args`.
pub fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_emoshift"))
        .args(args)
        .output()
        .expect("emoshift runs")
}

/// Runs `emoshift` and returns its stdout; fails the test with its stderr if it fails.
pub fn ok(args: &[&str]) -> String {
    let out = run(args);
    assert!(
        out.status.success(),
        "emoshift {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Runs `emoshift` with a progress line for every step and advance (as in a pipe, without
/// the interval that keeps a short run quiet), fails the test if it fails, and checks that
/// stderr holds each of `lines`.
pub fn shows_progress(args: &[&str], lines: &[&str]) {
    let out = Command::new(env!("CARGO_BIN_EXE_emoshift"))
        .args(args)
        .env("EMOSHIFT_PROGRESS_SECS", "0")
        .output()
        .expect("emoshift runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    for line in lines {
        assert!(err.contains(line), "no {line:?} in:\n{err}");
    }
}

/// A path as a command-line argument.
pub fn p(path: &Path) -> &str {
    path.to_str().expect("utf-8 path")
}

/// Pearson correlation of two series.
pub fn corr(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    sab / (saa * sbb).sqrt().max(1e-300)
}

/// Component series of `takes` (concatenated) from `emoshift project`, one per component.
pub fn project_series(model: &Path, takes: &[std::path::PathBuf]) -> Vec<Vec<f64>> {
    let mut series: Vec<Vec<f64>> = Vec::new();
    for take in takes {
        let csv = take.with_extension("components.csv");
        ok(&[
            "project",
            "--model",
            p(model),
            p(take),
            "--out",
            p(&csv),
            "--force",
        ]);
        let text = std::fs::read_to_string(&csv).expect("components csv");
        for line in text.lines().skip(1) {
            let values: Vec<f64> = line
                .split(',')
                .skip(2)
                .map(|v| v.parse().expect("number"))
                .collect();
            if series.is_empty() {
                series = vec![Vec::new(); values.len()];
            }
            for (s, v) in series.iter_mut().zip(values) {
                s.push(v);
            }
        }
    }
    series
}
