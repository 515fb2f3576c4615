//! Fit benchmarks at small sizes (seconds in all). The full 12,000 x 327 comparison against
//! scikit-learn is `scripts/bench-fit`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use ica_core::fit::{mixture, FastIcaParams, FitData};
use ica_core::whiten::{whiten, Components};

/// (frames, channels, components) per case.
const CASES: [(usize, usize, usize); 2] = [(2_000, 60, 6), (4_000, 120, 10)];

fn bench_fit(c: &mut Criterion) {
    let mut group = c.benchmark_group("fit");
    group.sample_size(10);
    for (frames, channels, m) in CASES {
        let mix = mixture::face_like(frames, channels, m, 0.2, 7);
        let data = FitData::new(&mix.samples, channels).expect("whole frames");
        let id = format!("{frames}x{channels}/m{m}");
        group.bench_function(BenchmarkId::new("whiten", &id), |b| {
            b.iter(|| whiten(&data, Components::Fixed(m)).expect("whitens"))
        });
        let params = FastIcaParams::default().n_components(m).keep_sources(false);
        group.bench_function(BenchmarkId::new("fit_4_restarts", &id), |b| {
            b.iter(|| params.fit(&data).expect("fits"))
        });
    }
    group.finish();
}

criterion_group!(benches, bench_fit);
criterion_main!(benches);
