//! Per-frame cost of project + edit + resynthesise (`Projector::process_into`) on random
//! models of 40/100/109/200 markers at 6/10/20 components, and of a frame with 20% of its
//! markers missing: the same markers every frame (an occlusion that lasts, the projector keeps
//! its factorisation) and a different 20% every frame (each frame factors anew). Budgets
//! (issue 35): 0.5 µs per full frame at 109 markers, 20 components; 1.5 µs masked.
//! `scripts/bench-project` prints medians against numpy without criterion.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use ica_core::{FrameEdit, IcaModel, Projector, TrainReport};
use nalgebra::DMatrix;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;
use std::time::Duration;

fn model(markers: usize, m: usize, seed: u64) -> IcaModel {
    let n = markers * 3;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let report = TrainReport::untrained(n, m);
    let mixing = DMatrix::from_fn(n, m, |_, _| rng.random_range(-1.0..1.0));
    let labels = (0..markers).map(|i| format!("m{i}")).collect();
    let mean = (0..n).map(|_| rng.random_range(900.0..1100.0)).collect();
    IcaModel::new(labels, 120.0, mean, mixing, report).expect("random mixing has full rank")
}

struct Setup {
    projector: Projector,
    edit: FrameEdit,
    frames: Vec<Vec<f32>>,
    mask: Vec<bool>,
    out_x: Vec<f32>,
    out_u: Vec<f32>,
}

fn setup(markers: usize, m: usize) -> Setup {
    let model = model(markers, m, 42);
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let frames = (0..64)
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
    let mask = (0..markers).map(|i| i % 5 == 0).collect();
    Setup {
        projector: Projector::new(&model),
        edit,
        frames,
        mask,
        out_x: vec![0.0; markers * 3],
        out_u: vec![0.0; m],
    }
}

fn full_frames(c: &mut Criterion) {
    let mut group = c.benchmark_group("project_edit_resynth");
    for markers in [40, 100, 109, 200] {
        for m in [6, 10, 20] {
            let mut s = setup(markers, m);
            let id = BenchmarkId::new(format!("{markers}_markers"), m);
            let mut f = 0;
            group.bench_function(id, |b| {
                b.iter(|| {
                    f = (f + 1) % s.frames.len();
                    let x = black_box(&s.frames[f]);
                    s.projector
                        .process_into(x, None, &s.edit, &mut s.out_x, &mut s.out_u)
                        .expect("sized buffers")
                })
            });
        }
    }
    group.finish();
}

fn masked_frames(c: &mut Criterion) {
    let mut group = c.benchmark_group("masked_20pct");
    for m in [6, 10, 20] {
        let mut s = setup(109, m);
        let mut f = 0;
        group.bench_function(BenchmarkId::new("109_markers", m), |b| {
            b.iter(|| {
                f = (f + 1) % s.frames.len();
                let x = black_box(&s.frames[f]);
                s.projector
                    .process_into(x, Some(&s.mask), &s.edit, &mut s.out_x, &mut s.out_u)
                    .expect("sized buffers")
            })
        });
    }
    group.finish();
    // A different fifth of the markers hidden in every frame (five masks in turn).
    let mut group = c.benchmark_group("masked_20pct_changing");
    for m in [6, 10, 20] {
        let mut s = setup(109, m);
        let masks: Vec<Vec<bool>> = (0..5)
            .map(|k| (0..109).map(|i| i % 5 == k).collect())
            .collect();
        let mut f = 0;
        group.bench_function(BenchmarkId::new("109_markers", m), |b| {
            b.iter(|| {
                f = (f + 1) % s.frames.len();
                let x = black_box(&s.frames[f]);
                let mask = &masks[f % masks.len()];
                s.projector
                    .process_into(x, Some(mask), &s.edit, &mut s.out_x, &mut s.out_u)
                    .expect("sized buffers")
            })
        });
    }
    group.finish();
}

fn config() -> Criterion {
    // Small sizes, stable numbers: shorter than criterion's defaults so the whole bench
    // takes about a minute on a 2-core machine.
    Criterion::default()
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
        .sample_size(50)
}

criterion_group! {
    name = benches;
    config = config();
    targets = full_frames, masked_frames
}
criterion_main!(benches);
