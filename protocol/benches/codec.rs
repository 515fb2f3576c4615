//! Frame codec cost at 109 markers: our encoder, our borrowed decoder (bare and through the
//! pre-scan), and rosc's decode of the very same bytes, in one criterion run.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use protocol::*;

const MARKERS: usize = 109;

fn frame() -> FrameBuf {
    let positions: Vec<f32> = (0..MARKERS * 3).map(|i| (i as f32).sin() * 80.0).collect();
    let mut f = FrameBuf::with_max_markers(MARKERS);
    f.set_frame(1, 8_333, &positions).expect("finite positions");
    f.set_missing(17, true);
    f
}

fn codec(c: &mut Criterion) {
    let f = frame();
    let mut bytes = Vec::with_capacity(1_500);
    encode_frame_into(&f, &mut bytes).expect("finite positions");
    let mut flat = Vec::with_capacity(1_500);
    encode_frame_flat_into(&f, &mut flat).expect("finite positions");
    let mut buf = FrameBuf::with_max_markers(MARKERS);
    let limits = Limits::default();

    let mut g = c.benchmark_group("frame_109");
    g.bench_function("encode", |b| {
        let mut out = Vec::with_capacity(1_500);
        b.iter(|| encode_frame_into(black_box(&f), &mut out).expect("finite"))
    });
    g.bench_function("decode", |b| {
        b.iter(|| decode_frame_into(black_box(&bytes), &mut buf).expect("valid"))
    });
    g.bench_function("prescan_and_decode", |b| {
        b.iter(|| {
            for m in messages(black_box(&bytes), &limits).expect("valid") {
                decode_frame_into(m.bytes, &mut buf).expect("valid");
            }
        })
    });
    g.bench_function("rosc_decode", |b| {
        b.iter(|| rosc::decoder::decode_udp(black_box(&bytes)).expect("valid"))
    });
    // what a rosc user must add to get positions out of the blob
    g.bench_function("rosc_decode_and_convert", |b| {
        b.iter(|| {
            let (_, p) = rosc::decoder::decode_udp(black_box(&bytes)).expect("valid");
            let rosc::OscPacket::Message(m) = p else {
                unreachable!("a frame is a message")
            };
            let Some(rosc::OscType::Blob(pos)) = m.args.get(3) else {
                unreachable!("positions are the fourth argument")
            };
            let v: Vec<f32> = pos
                .chunks_exact(4)
                .map(|c| f32::from_be_bytes([c[0], c[1], c[2], c[3]]))
                .collect();
            v
        })
    });
    g.bench_function("decode_flat", |b| {
        b.iter(|| decode_frame_into(black_box(&flat), &mut buf).expect("valid"))
    });
    g.bench_function("rosc_decode_flat", |b| {
        b.iter(|| rosc::decoder::decode_udp(black_box(&flat)).expect("valid"))
    });
    g.finish();
}

criterion_group!(benches, codec);
criterion_main!(benches);
