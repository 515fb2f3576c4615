//! Times a full fit (whitening + FastICA restarts) on a large face-like mixture and writes the
//! data, the true mixing and our unmixing to files, so `scripts/bench_fit.py` can time
//! scikit-learn on exactly the same data and score both with the Amari index.
//!
//! ```text
//! cargo run --release -p ica-core --example fit_timing -- \
//!     --out target/bench-fit --frames 12000 --channels 327 --m 6,10,20 --runs 5
//! ```
//!
//! Files per `m` (little-endian, row-major): `data_m{m}.f32` (frames x channels),
//! `mixing_m{m}.f64` (channels x m), `ours_unmixing_m{m}.f64` (m x channels). One JSON line per
//! `m` goes to stdout.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use ica_core::fit::{amari_index, mixture, FastIcaParams, FitData};
use ica_core::whiten::{whiten, Components};
use nalgebra::DMatrix;

struct Args {
    out: PathBuf,
    frames: usize,
    channels: usize,
    ms: Vec<usize>,
    runs: usize,
    seed: u64,
}

fn parse() -> Result<Args, String> {
    let mut args = Args {
        out: PathBuf::from("target/bench-fit"),
        frames: 12_000,
        channels: 327,
        ms: vec![6, 10, 20],
        runs: 5,
        seed: 1,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let value = it.next().ok_or(format!("{flag} needs a value"))?;
        let bad = |e: &dyn std::fmt::Display| format!("{flag} {value}: {e}");
        match flag.as_str() {
            "--out" => args.out = PathBuf::from(&value),
            "--frames" => args.frames = value.parse().map_err(|e| bad(&e))?,
            "--channels" => args.channels = value.parse().map_err(|e| bad(&e))?,
            "--runs" => args.runs = value.parse().map_err(|e| bad(&e))?,
            "--seed" => args.seed = value.parse().map_err(|e| bad(&e))?,
            "--m" => {
                args.ms = value
                    .split(',')
                    .map(|s| s.trim().parse().map_err(|e| bad(&e)))
                    .collect::<Result<_, _>>()?
            }
            _ => return Err(format!("unknown flag {flag}")),
        }
    }
    if args.runs == 0 {
        return Err("--runs must be at least 1".into());
    }
    Ok(args)
}

fn write_f64(path: &Path, m: &DMatrix<f64>) -> std::io::Result<()> {
    let mut bytes = Vec::with_capacity(m.len() * 8);
    for r in 0..m.nrows() {
        for c in 0..m.ncols() {
            bytes.extend_from_slice(&m[(r, c)].to_le_bytes());
        }
    }
    std::fs::write(path, bytes)
}

fn write_f32(path: &Path, v: &[f32]) -> std::io::Result<()> {
    let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
    std::fs::write(path, bytes)
}

/// CPU time this thread has run, in seconds (Linux `schedstat`; NaN elsewhere). On a loaded
/// machine it is steadier than wall time, which also counts time spent waiting for a core.
fn thread_cpu_s() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(f64::NAN, |ns| ns * 1e-9)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let args = match parse() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("fit_timing: {e}");
            std::process::exit(2);
        }
    };
    if let Err(e) = run(&args) {
        eprintln!("fit_timing: {e}");
        std::process::exit(1);
    }
}

fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    std::fs::create_dir_all(&args.out)?;
    let stdout = std::io::stdout();
    for &m in &args.ms {
        let mix = mixture::face_like(args.frames, args.channels, m, 0.2, args.seed + m as u64);
        write_f32(&args.out.join(format!("data_m{m}.f32")), &mix.samples)?;
        write_f64(&args.out.join(format!("mixing_m{m}.f64")), &mix.mixing)?;
        let data = FitData::new(&mix.samples, mix.channels)?;
        let params = FastIcaParams::default().n_components(m).keep_sources(false);
        let (mut times, mut white_times, mut cpu_times) = (Vec::new(), Vec::new(), Vec::new());
        let mut last = None;
        for _ in 0..args.runs {
            let t0 = Instant::now();
            let w = whiten(&data, Components::Fixed(m))?;
            white_times.push(t0.elapsed().as_secs_f64());
            drop(w);
            let (t0, c0) = (Instant::now(), thread_cpu_s());
            last = Some(params.fit(&data)?);
            times.push(t0.elapsed().as_secs_f64());
            cpu_times.push(thread_cpu_s() - c0);
        }
        let out = last.ok_or("no run")?;
        write_f64(
            &args.out.join(format!("ours_unmixing_m{m}.f64")),
            &out.unmixing,
        )?;
        let ai = amari_index(&(&out.unmixing * &mix.mixing)).unwrap_or(f64::NAN);
        let r = &out.report;
        let its: Vec<String> = r
            .restarts
            .iter()
            .map(|x| x.iterations.to_string())
            .collect();
        let conv: Vec<String> = r.restarts.iter().map(|x| x.converged.to_string()).collect();
        let refine = r.restarts[r.best_restart]
            .refinement
            .as_ref()
            .map_or(0, |x| x.iterations);
        let explored = r.restarts[r.best_restart].frames;
        writeln!(
            stdout.lock(),
            "{{\"m\":{m},\"frames\":{},\"channels\":{},\"runs\":{},\"median_s\":{:.6},\
             \"cpu_median_s\":{:.6},\
             \"whiten_median_s\":{:.6},\"amari\":{:.6},\"iterations\":[{}],\"converged\":[{}],\
             \"best_restart\":{},\"explored_frames\":{},\"refine_iterations\":{}}}",
            args.frames,
            args.channels,
            args.runs,
            median(&mut times),
            median(&mut cpu_times),
            median(&mut white_times),
            ai,
            its.join(","),
            conv.join(","),
            r.best_restart,
            explored,
            refine
        )?;
    }
    Ok(())
}
