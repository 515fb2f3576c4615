//! Times the streaming fit pass by pass on a long face-like take at 109 markers, on one thread,
//! and checks it against the in-memory fit. A reference for a daemon driver: the same
//! [`StreamFit`] loop, with the folds done serially.
//!
//! ```text
//! cargo run --release -p ica-core --example stream_timing -- 200000
//! ```

use std::time::Instant;

use ica_core::fit::{mixture, FastIcaParams, FitData, Pass, StreamFit};

const CHANNELS: usize = 327;
const CHUNK: usize = 8_192;

fn main() {
    let frames: usize = std::env::args()
        .nth(1)
        .map_or(200_000, |a| a.parse().expect("frame count"));
    let mix = mixture::face_like(frames, CHANNELS, 20, 0.2, 11);
    let data = FitData::new(&mix.samples, CHANNELS).expect("whole frames");
    let params = FastIcaParams::default().n_components(20).seed(1);
    let chunks: Vec<FitData<'_, f32>> = (0..frames)
        .step_by(CHUNK)
        .map(|s| data.slice_frames(s, (s + CHUNK).min(frames)))
        .collect();
    let mut fit = StreamFit::new(&params, CHANNELS).expect("params");
    let mut spill: Vec<Vec<f32>> = Vec::new();
    let mut seconds = [0.0f64; 4];
    let started = Instant::now();
    loop {
        let t = Instant::now();
        let pass = fit.poll_pass();
        match pass {
            Pass::Moments => {
                let mut moments = fit.moments();
                chunks
                    .iter()
                    .for_each(|c| moments.add_chunk(c).expect("finite"));
                fit.handle_moments(moments).expect("whitens");
            }
            Pass::Whiten => {
                let w = fit.whitener().expect("whitening pass");
                let mut sub = fit.subsample().expect("whitening pass");
                let mut scratch = Vec::new();
                spill = chunks
                    .iter()
                    .map(|c| {
                        let mut z = Vec::new();
                        w.whiten_into(c, &mut z, &mut scratch).expect("whitens");
                        sub.push(&z).expect("whole frames");
                        z
                    })
                    .collect();
                fit.handle_whitened(sub).expect("restarts");
            }
            Pass::Update => {
                let mut acc = fit.update_accumulator().expect("update pass");
                spill.iter().for_each(|z| acc.add_chunk(z).expect("frames"));
                fit.handle_update(acc).expect("iterates");
            }
            Pass::Sources => {
                let mut sums = fit.source_moments().expect("sources pass");
                spill
                    .iter()
                    .for_each(|z| sums.add_chunk(z).expect("frames"));
                fit.handle_sources(sums).expect("assembles");
            }
            Pass::Done => break,
        }
        let slot = match pass {
            Pass::Moments => 0,
            Pass::Whiten => 1,
            Pass::Update => 2,
            _ => 3,
        };
        seconds[slot] += t.elapsed().as_secs_f64();
    }
    let total = started.elapsed().as_secs_f64();
    let out = fit.finish().expect("done");
    let best = &out.report.restarts[out.report.best_restart];
    let iterations = best
        .refinement
        .as_ref()
        .map_or(best.iterations, |r| r.iterations);
    println!(
        "{frames} frames x {CHANNELS} channels, m = {}: {total:.2} s on one thread \
         (statistics {:.2} s = {:.0} frames/s, whitening + restarts {:.2} s, \
         {iterations} update passes {:.2} s, sources {:.2} s)",
        out.report.components,
        seconds[0],
        frames as f64 / seconds[0],
        seconds[1],
        seconds[2],
        seconds[3],
    );
    let t = Instant::now();
    let in_memory = params.keep_sources(false).fit(&data).expect("fits");
    let diff = (&out.mixing - &in_memory.mixing).amax() / in_memory.mixing.amax();
    println!(
        "in-memory fit {:.2} s; streaming vs in-memory mixing: {diff:.1e} relative",
        t.elapsed().as_secs_f64()
    );
}
