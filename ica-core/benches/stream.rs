//! Streaming fit kernels per 10,000 frames at 109 markers (327 channels), m = 20: the moments
//! pass (the dominant cost: a 327 x 327 syrk per frame), the whitening pass, and one FastICA
//! iteration and the sources pass over whitened f32 frames. Issue 18's budget: a 4-hour
//! session (1.7 M frames) trains in under 2 minutes on 2 cores.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use ica_core::fastica::{SourceMoments, UpdateAccumulator};
use ica_core::fit::{mixture, Contrast, FitData};
use ica_core::whiten::{Components, Moments, Whitener};
use nalgebra::DMatrix;

const FRAMES: usize = 10_000;
const CHANNELS: usize = 327;
const M: usize = 20;
/// Frames per chunk, as a driver reading files would pass them.
const CHUNK: usize = 2_000;

fn bench_stream(c: &mut Criterion) {
    let mix = mixture::face_like(FRAMES, CHANNELS, M, 0.2, 7);
    let data = FitData::new(&mix.samples, CHANNELS).expect("whole frames");
    let chunks: Vec<FitData<'_, f32>> = (0..FRAMES)
        .step_by(CHUNK)
        .map(|s| data.slice_frames(s, s + CHUNK))
        .collect();
    let mut all = Moments::new(CHANNELS);
    all.add_chunk(&data).expect("finite");
    let whitener = Whitener::from_moments(&all, Components::Fixed(M)).expect("whitens");
    let (mut z, mut scratch) = (Vec::<f32>::new(), Vec::new());
    whitener
        .whiten_into(&data, &mut z, &mut scratch)
        .expect("whitens");
    // A rotation away from the identity, as mid-iteration.
    let rotation = DMatrix::<f64>::from_fn(M, M, |i, j| ((i * 7 + j * 3) % 11) as f64 - 5.0)
        .qr()
        .q();

    let mut group = c.benchmark_group("stream_10k_frames_327ch_m20");
    group.sample_size(20);
    group.throughput(Throughput::Elements(FRAMES as u64));
    let mut moments = Moments::new(CHANNELS);
    moments.add_chunk(&chunks[0]).expect("finite");
    group.bench_function("moments", |b| {
        b.iter(|| {
            for chunk in &chunks {
                moments.add_chunk(black_box(chunk)).expect("finite");
            }
        })
    });
    let mut out = Vec::<f32>::new();
    group.bench_function("whiten", |b| {
        b.iter(|| {
            for chunk in &chunks {
                whitener
                    .whiten_into(black_box(chunk), &mut out, &mut scratch)
                    .expect("whitens");
            }
        })
    });
    assert_eq!(
        z.len(),
        FRAMES * M,
        "the whitened frames the next cases read"
    );
    group.bench_function("fastica_iteration", |b| {
        b.iter(|| {
            let mut acc = UpdateAccumulator::new(&rotation, Contrast::LogCosh);
            for chunk in z.chunks(CHUNK * M) {
                acc.add_chunk(black_box(chunk)).expect("whole frames");
            }
            acc.finish().expect("frames")
        })
    });
    group.bench_function("sources", |b| {
        b.iter(|| {
            let mut sums = SourceMoments::new(&rotation, Contrast::LogCosh);
            for chunk in z.chunks(CHUNK * M) {
                sums.add_chunk(black_box(chunk)).expect("whole frames");
            }
            (sums.negentropy(), sums.skewness())
        })
    });
    group.finish();
}

criterion_group!(benches, bench_stream);
criterion_main!(benches);
