//! NatNet frame codec cost for a 109-marker face: one markerset (plus Motive's `all`) and the
//! same markers as labelled markers, in the NatNet 3.0 and 4.1 layouts.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use protocol::natnet::*;

const MARKERS: usize = 109;

fn face() -> FrameOfData {
    let positions: Vec<[f32; 3]> = (0..MARKERS)
        .map(|i| {
            let t = i as f32;
            [t.sin() * 0.08, 1.6 + t.cos() * 0.1, 0.05]
        })
        .collect();
    let mut f = FrameOfData::with_capacity(MARKERS, 1);
    f.frame_number = 162_734;
    f.push_markerset("face", &positions);
    f.push_markerset("all", &positions);
    f.labeled_markers = positions
        .iter()
        .enumerate()
        .map(|(i, &position)| LabeledMarker {
            id: 1 << 16 | (i as u32 + 1),
            position,
            size: 0.003,
            params: MarkerParams(0x0a),
            residual: 0.0002,
        })
        .collect();
    f.timestamp = 1356.125;
    f
}

fn natnet(c: &mut Criterion) {
    let f = face();
    let mut g = c.benchmark_group("natnet_frame_109");
    for (label, v) in [("v3_0", NatNetVersion::V3_0), ("v4_1", NatNetVersion::V4_1)] {
        let mut bytes = Vec::with_capacity(4_096);
        encode_frame_into(&f, v, &mut bytes).expect("encodable");
        let mut buf = FrameOfData::with_capacity(MARKERS, 1);
        g.bench_function(format!("decode_{label}"), |b| {
            b.iter(|| decode_frame_into(black_box(&bytes), v, &mut buf).expect("valid"))
        });
        let mut mm = Vec::with_capacity(MARKERS * 3);
        g.bench_function(format!("decode_{label}_to_mm"), |b| {
            b.iter(|| {
                decode_frame_into(black_box(&bytes), v, &mut buf).expect("valid");
                let face = buf.markerset(0).expect("face");
                positions_mm_into(face.positions, &mut mm);
            })
        });
        let mut out = Vec::with_capacity(4_096);
        g.bench_function(format!("encode_{label}"), |b| {
            b.iter(|| encode_frame_into(black_box(&f), v, &mut out).expect("encodable"))
        });
    }
    g.finish();
}

criterion_group!(benches, natnet);
criterion_main!(benches);
