//! Issue 4 acceptance: on paired synthetic sessions, `analyze` labels the components the
//! generator's truth says they are, and `edit --to-emotion` turns a frustrated take into one close
//! to the generator's happy rendering at the same timing.

use std::path::Path;

use replay::synth::{load_truth, Synth, SynthParams};

use crate::common::{corr, ok as emoshift, project_series};

fn params(seed: u64, sentences: usize) -> SynthParams {
    SynthParams {
        seed,
        sentences,
        ..SynthParams::default()
    }
}

/// synth -> train (m = 8) -> analyze --write-model, in `dir`.
fn session(dir: &Path, seed: u64, sentences: usize) {
    let d = dir.to_str().expect("utf-8 temp path");
    emoshift(&[
        "synth",
        "--out",
        d,
        "--seed",
        &seed.to_string(),
        "--sentences",
        &sentences.to_string(),
    ]);
    let manifest = format!("{d}/session.toml");
    let model = format!("{d}/model.json");
    emoshift(&[
        "train",
        "--manifest",
        &manifest,
        "--out",
        &model,
        "--components",
        "8",
    ]);
    emoshift(&[
        "analyze",
        "--model",
        &model,
        "--manifest",
        &manifest,
        "--out",
        &format!("{d}/report"),
        "--write-model",
    ]);
}

/// Component series of every take (concatenated) from `emoshift project`.
fn components(dir: &Path, takes: &[String]) -> Vec<Vec<f64>> {
    let paths: Vec<_> = takes.iter().map(|n| dir.join(format!("{n}.c3d"))).collect();
    project_series(&dir.join("model.json"), &paths)
}

/// Sentences per session: 12 sentences x 3 emotions is about 12,800 frames, the size of the
/// method's own data set (11,883 frames).
const SENTENCES: usize = 12;

#[test]
fn analyze_labels_match_the_generator_truth() {
    for seed in [3, 5, 11, 21] {
        let dir = tempfile::tempdir().expect("temp dir");
        session(dir.path(), seed, SENTENCES);
        let truth = load_truth(dir.path()).expect("truth");
        let names: Vec<String> = truth.takes.iter().map(|t| t.name.clone()).collect();
        let comps = components(dir.path(), &names);
        let report: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(dir.path().join("report/report.json")).expect("report"),
        )
        .expect("json");
        let roles: Vec<String> = report["components"]
            .as_array()
            .expect("components list")
            .iter()
            .map(|c| c["role"].as_str().expect("role").to_string())
            .collect();
        check_figures(dir.path(), &report);
        let with_role =
            |role: &str| -> Vec<usize> { (0..roles.len()).filter(|&k| roles[k] == role).collect() };
        for (s, info) in truth.mixing.sources.iter().enumerate() {
            if info.role == "head" || info.role == "speech" {
                continue;
            }
            let source: Vec<f64> = truth.takes.iter().flat_map(|t| t.source(s)).collect();
            let (best, r) = comps
                .iter()
                .enumerate()
                .map(|(k, c)| (k, corr(c, &source).abs()))
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .expect("components");
            let fit = r_squared(&source, &with_role(&info.role), &comps);
            eprintln!(
                "seed {seed}: {} -> c{best} {} |corr| {r:.3}, R² on {} components {fit:.3}",
                info.name, roles[best], info.role
            );
            assert_eq!(
                roles[best], info.role,
                "seed {seed}: {} roles {roles:?}",
                info.name
            );
            let floor = match info.role.as_str() {
                "emotion" | "eyelids" => 0.9,
                // Brow raises come with stressed syllables (r = 0.47 with the jaw in the
                // generator, as in real speech), so their component carries some speech.
                _ => 0.5,
            };
            assert!(
                fit > floor,
                "seed {seed}: {} R² {fit:.3}; roles {roles:?}",
                info.name
            );
        }
        // The speech sources share one viseme sequence, so ICA need not split them one to one
        // (the method finds several speech components too): the speech-labelled components
        // must carry most of the mouth motion that speech causes. Brow emphasis comes with
        // stressed syllables, so on some seeds one component mixes emphasis and speech and is
        // labelled eyebrows; together the two roles must hold nearly all of it.
        let speech = with_role("speech");
        let fit = speech_mouth_r_squared(&truth, &speech, &comps);
        let mut both = speech.clone();
        both.extend(with_role("eyebrows"));
        let fit_both = speech_mouth_r_squared(&truth, &both, &comps);
        eprintln!(
            "seed {seed}: speech-driven mouth motion R² on speech components {fit:.3}, with eyebrow components {fit_both:.3}"
        );
        assert!(
            fit > 0.6,
            "seed {seed}: speech R² {fit:.3}; roles {roles:?}"
        );
        assert!(
            fit_both > 0.9,
            "seed {seed}: speech R² with eyebrows {fit_both:.3}"
        );
    }
}

/// The bar charts show, panel after panel, d_emotion and |d_mouth|, |d_eyebrows|, |d_eyelids|
/// of every component, as report.json has them; the HTML page shows both figures.
fn check_figures(dir: &Path, report: &serde_json::Value) {
    let svg = std::fs::read_to_string(dir.join("report/components.svg")).expect("svg");
    let values: Vec<f64> = svg
        .split("data-value=\"")
        .skip(1)
        .map(|rest| {
            rest.split('"')
                .next()
                .expect("quoted")
                .parse()
                .expect("number")
        })
        .collect();
    let comps = report["components"].as_array().expect("components");
    let mut expected = Vec::new();
    for metric in ["d_emotion", "mouth", "eyebrows", "eyelids"] {
        for c in comps {
            let v = if metric == "d_emotion" {
                c["d_emotion"].as_f64().expect("paired session")
            } else {
                c["d_region"][metric].as_f64().expect("region metric").abs()
            };
            expected.push(v);
        }
    }
    assert_eq!(
        values.len(),
        expected.len(),
        "one bar per component per panel"
    );
    for (v, e) in values.iter().zip(&expected) {
        assert!((v - e).abs() < 1e-5, "bar {v} vs report {e}");
    }
    let html = std::fs::read_to_string(dir.join("report/report.html")).expect("html");
    assert!(html.contains("src=\"components.svg\"") && html.contains("src=\"timeline.svg\""));
    let timeline = std::fs::read_to_string(dir.join("report/timeline.svg")).expect("timeline");
    assert_eq!(
        timeline.matches("<path ").count(),
        comps.len(),
        "one series per component"
    );
}

/// R² of the true speech-driven mouth displacement (all mouth channels together) regressed on
/// the chosen components.
fn speech_mouth_r_squared(
    truth: &replay::synth::SessionTruth,
    chosen: &[usize],
    comps: &[Vec<f64>],
) -> f64 {
    let mix = &truth.mixing;
    let speech = mix.role_indices("speech");
    let mouth: Vec<usize> = mix.regions["mouth"]
        .iter()
        .filter_map(|l| mix.labels.iter().position(|x| x == l))
        .collect();
    let sources: Vec<Vec<f64>> = speech
        .iter()
        .map(|&s| truth.takes.iter().flat_map(|t| t.source(s)).collect())
        .collect();
    let (mut resid, mut total) = (0.0, 0.0);
    for &m in &mouth {
        for axis in 0..3 {
            let row = &mix.matrix[m * 3 + axis];
            let y: Vec<f64> = (0..sources[0].len())
                .map(|t| {
                    speech
                        .iter()
                        .zip(&sources)
                        .map(|(&s, src)| row[s] * src[t])
                        .sum()
                })
                .collect();
            let var: f64 = {
                let mean = y.iter().sum::<f64>() / y.len() as f64;
                y.iter().map(|v| (v - mean).powi(2)).sum()
            };
            resid += (1.0 - r_squared(&y, chosen, comps)) * var;
            total += var;
        }
    }
    1.0 - resid / total.max(1e-300)
}

/// Share of `y`'s variance explained by a least-squares fit on the chosen component series.
fn r_squared(y: &[f64], chosen: &[usize], comps: &[Vec<f64>]) -> f64 {
    if chosen.is_empty() {
        return 0.0;
    }
    let n = y.len();
    let x = nalgebra::DMatrix::from_fn(n, chosen.len() + 1, |t, j| {
        if j == 0 {
            1.0
        } else {
            comps[chosen[j - 1]][t]
        }
    });
    let yv = nalgebra::DVector::from_column_slice(y);
    let beta = (x.transpose() * &x)
        .lu()
        .solve(&(x.transpose() * &yv))
        .expect("regression");
    let resid = &yv - &x * beta;
    let mean = yv.mean();
    let total: f64 = yv.iter().map(|v| (v - mean).powi(2)).sum();
    1.0 - resid.norm_squared() / total.max(1e-300)
}

/// RMS over frames and markers of the 3-D distance between two equally shaped takes.
fn rms_mm(a: &replay::Take, b: &replay::Take) -> f64 {
    let n = a.missing.len() as f64;
    let sq: f64 = a
        .positions
        .chunks_exact(3)
        .zip(b.positions.chunks_exact(3))
        .map(|(p, q)| (0..3).map(|i| f64::from(p[i] - q[i]).powi(2)).sum::<f64>())
        .sum();
    (sq / n).sqrt()
}

#[test]
fn to_emotion_turns_frustrated_into_happy_at_the_same_timing() {
    let seed = 5;
    let dir = tempfile::tempdir().expect("temp dir");
    session(dir.path(), seed, 6);
    let d = dir.path().to_str().expect("utf-8");
    let synth = Synth::new(params(seed, 6)).expect("synth");
    let mut worst: f64 = 0.0;
    for sentence in 0..3 {
        let frustrated = synth.take_spec(sentence, "frustrated").expect("spec");
        let happy = synth
            .take_spec(sentence, "happy")
            .expect("spec")
            .with_timing_of(&frustrated);
        let original = synth.render_take(&frustrated).expect("render").take;
        let target = synth.render_take(&happy).expect("render").take;
        let name = synth.take_name(sentence, "frustrated");
        let edited_path = format!("{d}/{name}_to_happy.c3d");
        emoshift(&[
            "edit",
            "--model",
            &format!("{d}/model.json"),
            &format!("{d}/{name}.c3d"),
            "--out",
            &edited_path,
            "--to-emotion",
            "happy",
        ]);
        let edited = replay::load(Path::new(&edited_path)).expect("edited take");
        let displacement = rms_mm(&original, &target);
        let error = rms_mm(&edited, &target);
        let fraction = error / displacement;
        eprintln!("sentence {sentence}: emotion displacement {displacement:.3} mm, error {error:.3} mm, fraction {fraction:.3}");
        worst = worst.max(fraction);
    }
    // The edit cannot remove the 0.2 mm sensor noise or the PCA residual, which are part of
    // the error; a third of the emotion-induced displacement is a clear, honest bar.
    assert!(worst < 0.35, "worst error fraction {worst:.3}");
}

#[test]
fn dtw_aligns_paired_takes_to_their_known_warps() {
    let synth = Synth::new(params(13, 3)).expect("synth");
    let mut errors = Vec::new();
    for sentence in 0..3 {
        let a = synth
            .render_take(&synth.take_spec(sentence, "happy").expect("spec"))
            .expect("render");
        let b = synth
            .render_take(&synth.take_spec(sentence, "frustrated").expect("spec"))
            .expect("render");
        // Align on the markers themselves (each take's mean removed), as no model is needed
        // to test the alignment.
        let series = |t: &replay::Take| -> Vec<f64> {
            let n = t.positions.len() / t.n_frames();
            let mut mean = vec![0.0; n];
            for row in t.positions.chunks_exact(n) {
                for (m, v) in mean.iter_mut().zip(row) {
                    *m += f64::from(*v) / t.n_frames() as f64;
                }
            }
            t.positions
                .chunks_exact(n)
                .flat_map(|row| {
                    row.iter()
                        .zip(&mean)
                        .map(|(v, m)| f64::from(*v) - m)
                        .collect::<Vec<_>>()
                })
                .collect()
        };
        let dim = a.take.n_markers() * 3;
        let band = (a.take.n_frames().max(b.take.n_frames()) as f64 * 0.25) as usize;
        let al = ica_core::dtw::align(&series(&a.take), &series(&b.take), dim, Some(band))
            .expect("aligns");
        let rate = a.take.rate_hz;
        for &(i, j) in &al.path {
            errors.push((a.truth.warp[i] - b.truth.warp[j]).abs() * rate);
        }
    }
    errors.sort_by(f64::total_cmp);
    let median = errors[errors.len() / 2];
    let p95 = errors[errors.len() * 95 / 100];
    eprintln!("DTW alignment error: median {median:.2} frames, p95 {p95:.2} frames");
    // The takes' own timing differs by up to ±20 % (tens of frames); aligned, matched frames
    // show the same canonical moment to within a couple of frames.
    assert!(median <= 1.5, "median {median:.2} frames");
    assert!(p95 <= 5.0, "p95 {p95:.2} frames");
}
