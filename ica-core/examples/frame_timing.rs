//! Median nanoseconds per frame of `Projector::process_into` (project + translate one
//! component + resynthesise), full frames and frames with 20% of the markers missing, on
//! random models. Plain output for `scripts/bench-project`, one line per size:
//!
//! ```text
//! rust markers=109 m=20 full_ns=912.3 full_min_ns=880.0 masked_ns=6950.1 masked_min_ns=6500.2
//! ```
//!
//! Usage: `cargo run --release -p ica-core --example frame_timing -- [markers] [m...]`
//! (defaults: 109 markers, m = 6 10 20).

use ica_core::{FrameEdit, IcaModel, Projector, TrainReport};
use nalgebra::DMatrix;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;
use std::time::Instant;

/// Frames per timed batch, and batches whose per-frame times give the median.
const BATCH: usize = 2_000;
const BATCHES: usize = 101;

fn model(markers: usize, m: usize) -> IcaModel {
    let n = markers * 3;
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let report = TrainReport::untrained(n, m);
    let mixing = DMatrix::from_fn(n, m, |_, _| rng.random_range(-1.0..1.0));
    let labels = (0..markers).map(|i| format!("m{i}")).collect();
    let mean = (0..n).map(|_| rng.random_range(900.0..1100.0)).collect();
    IcaModel::new(labels, 120.0, mean, mixing, report).expect("random mixing has full rank")
}

/// (median, min) over batches of (batch time / BATCH), in ns. The minimum is printed too
/// because on a shared machine the median carries other processes' load.
fn timing_ns(mut frame: impl FnMut(usize)) -> (f64, f64) {
    for f in 0..BATCH {
        frame(f);
    }
    let mut per_frame: Vec<f64> = (0..BATCHES)
        .map(|_| {
            let start = Instant::now();
            for f in 0..BATCH {
                frame(f);
            }
            start.elapsed().as_nanos() as f64 / BATCH as f64
        })
        .collect();
    per_frame.sort_by(f64::total_cmp);
    (per_frame[BATCHES / 2], per_frame[0])
}

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| {
            a.parse()
                .expect("arguments are integers: markers then m values")
        })
        .collect();
    let markers = args.first().copied().unwrap_or(109);
    let ms = if args.len() > 1 {
        args[1..].to_vec()
    } else {
        vec![6, 10, 20]
    };
    for m in ms {
        let model = model(markers, m);
        let mut p = Projector::new(&model);
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let frames: Vec<Vec<f32>> = (0..64)
            .map(|_| {
                model
                    .mean()
                    .iter()
                    .map(|&v| v as f32 + rng.random_range(-5.0..5.0))
                    .collect()
            })
            .collect();
        let mut edit = FrameEdit::identity(m);
        edit.set_offset(m / 2, 1.5).expect("in range");
        let mask: Vec<bool> = (0..markers).map(|i| i % 5 == 0).collect();
        let (mut out_x, mut out_u) = (vec![0.0_f32; markers * 3], vec![0.0_f32; m]);
        let mut run = |f: usize, mask: Option<&[bool]>| {
            let x = black_box(&frames[f % frames.len()]);
            let status = p.process_into(x, mask, &edit, &mut out_x, &mut out_u);
            black_box(status.expect("buffers sized from the model"));
        };
        let (full, full_min) = timing_ns(|f| run(f, None));
        let (masked, masked_min) = timing_ns(|f| run(f, Some(&mask)));
        println!(
            "rust markers={markers} m={m} full_ns={full:.1} full_min_ns={full_min:.1} \
             masked_ns={masked:.1} masked_min_ns={masked_min:.1}"
        );
    }
}
