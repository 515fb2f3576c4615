//! What to re-record after a session's analysis, in plain words ([`advise`]): emotions that
//! cannot be told apart, and takes whose emotion level is an outlier for their emotion (a
//! robust z-score over the emotion's takes, per emotion component). Gappy takes never get
//! this far: [`super::check`] refuses them when they are recorded.

use std::collections::BTreeMap;

use crate::offline::analysis::Report;

/// A take's modified z-score (Iglewicz and Hoaglin: 0.6745 x distance from the median over
/// the median absolute deviation) above which it is an outlier.
pub const OUTLIER_Z: f64 = 3.5;

/// What to redo.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Advice {
    /// Plain lines for the operator.
    pub lines: Vec<String>,
    /// The take files to re-record (for `--redo`).
    pub redo: Vec<String>,
}

/// Reads the analysis for what to redo.
pub fn advise(report: &Report) -> Advice {
    let mut advice = Advice::default();
    let Some(space) = &report.space else {
        advice.lines.push(format!(
            "the emotions could not be measured ({}): record every sentence in every emotion",
            report.emotion_note
        ));
        return advice;
    };
    for pair in &space.indistinct {
        let takes: Vec<String> = report
            .takes
            .iter()
            .filter(|t| t.emotion == pair.b)
            .map(|t| t.file.clone())
            .collect();
        advice.lines.push(format!(
            "{} and {} cannot be told apart (their faces differ by {:.2}, less than they vary \
             within each): re-record the {} takes, playing {} more distinctly",
            pair.a,
            pair.b,
            pair.distance,
            takes.len(),
            pair.b
        ));
        advice.redo.extend(takes);
    }
    for (file, emotion, z) in outliers(report, &space.components) {
        advice.lines.push(format!(
            "{file}: its {emotion} is unlike the other {emotion} takes (z = {z:.1}): re-record it"
        ));
        if !advice.redo.contains(&file) {
            advice.redo.push(file);
        }
    }
    advice
}

/// Takes whose level on some emotion component is an outlier among their emotion's takes.
fn outliers(report: &Report, components: &[usize]) -> Vec<(String, String, f64)> {
    let mut by_emotion: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
    for (i, t) in report.takes.iter().enumerate() {
        by_emotion.entry(&t.emotion).or_default().push(i);
    }
    let mut out = Vec::new();
    for (emotion, takes) in by_emotion {
        if takes.len() < 4 {
            continue;
        }
        let mut worst = vec![0.0f64; takes.len()];
        for &c in components {
            let x: Vec<f64> = takes
                .iter()
                .map(|&i| {
                    report.takes[i]
                        .component_means
                        .get(c)
                        .copied()
                        .unwrap_or(0.0)
                })
                .collect();
            let med = median(&x);
            let mad = median(&x.iter().map(|v| (v - med).abs()).collect::<Vec<_>>());
            if mad <= f64::EPSILON {
                continue;
            }
            for (w, v) in worst.iter_mut().zip(&x) {
                *w = w.max(0.6745 * (v - med).abs() / mad);
            }
        }
        for (&i, &z) in takes.iter().zip(&worst) {
            if z > OUTLIER_Z {
                out.push((report.takes[i].file.clone(), emotion.to_string(), z));
            }
        }
    }
    out
}

fn median(x: &[f64]) -> f64 {
    let mut v = x.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => 0.0,
        _ if n % 2 == 1 => v[n / 2],
        _ => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_median_and_a_robust_outlier() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
        let x = [1.0, 1.1, 0.9, 1.05, 0.95, 1.0, 5.0];
        let med = median(&x);
        let mad = median(&x.iter().map(|v| (v - med).abs()).collect::<Vec<_>>());
        assert!(0.6745 * (5.0 - med) / mad > OUTLIER_Z);
        assert!(0.6745 * (1.1 - med) / mad < OUTLIER_Z);
    }
}
