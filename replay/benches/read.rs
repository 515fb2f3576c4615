//! Reading takes from memory: 2,400 frames (20 s at 120 Hz) of 109 markers with a few gaps, as
//! C3D (the cross-checked reader and the decoder alone), TRC and CSV; throughput is the file's
//! bytes. The baseline in the same run is a copy of the C3D bytes, what "memory speed" means
//! for a reader that must at least look at every byte once.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use replay::Take;

const MARKERS: usize = 109;
const FRAMES: usize = 2_400;

/// A face-sized take with smooth motion and about 1 % of samples missing.
fn take() -> Take {
    let labels = (0..MARKERS).map(|m| format!("Marker{m:03}")).collect();
    let mut take = Take::new(labels, 120.0, 1);
    let (mut xyz, mut gone) = (vec![0.0f32; MARKERS * 3], vec![false; MARKERS]);
    for f in 0..FRAMES {
        for m in 0..MARKERS {
            let t = f as f32 / 120.0;
            let phase = m as f32 * 0.37;
            xyz[m * 3] = 40.0 * (phase).cos() + 2.0 * (3.1 * t + phase).sin();
            xyz[m * 3 + 1] = 1500.0 + 30.0 * (phase).sin() + 1.5 * (2.3 * t).cos();
            xyz[m * 3 + 2] = 80.0 + 0.5 * (5.0 * t + phase).sin();
            gone[m] = (f * 31 + m * 17) % 97 == 0;
        }
        take.push_frame(&xyz, &gone);
    }
    take
}

fn bench_read(c: &mut Criterion) {
    let take = take();
    let mut c3d = Vec::new();
    replay::c3d::write(&take, &mut c3d).expect("writes");
    let mut trc = Vec::new();
    replay::trc::write(&take, &mut trc).expect("writes");
    let mut csv = Vec::new();
    replay::csv::write(&take, &mut csv).expect("writes");

    let mut group = c.benchmark_group("read_2400_frames_109_markers");
    group.sample_size(20);
    group.throughput(Throughput::Bytes(c3d.len() as u64));
    group.bench_function("memcpy_c3d_bytes", |b| {
        b.iter(|| black_box(c3d.clone()));
    });
    group.bench_function("c3d_cross_checked", |b| {
        b.iter(|| replay::c3d::read_with_info(black_box(&c3d)).expect("reads"));
    });
    group.bench_function("c3d_own", |b| {
        b.iter(|| replay::c3d::read_own(black_box(c3d.as_slice())).expect("reads"));
    });
    group.throughput(Throughput::Bytes(trc.len() as u64));
    group.bench_function("trc", |b| {
        b.iter(|| replay::trc::read(black_box(trc.as_slice())).expect("reads"));
    });
    group.throughput(Throughput::Bytes(csv.len() as u64));
    group.bench_function("csv", |b| {
        b.iter(|| replay::csv::read(black_box(csv.as_slice())).expect("reads"));
    });
    group.finish();
}

criterion_group!(benches, bench_read);
criterion_main!(benches);
