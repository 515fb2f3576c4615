//! The whole live frame path (decode → map → project → edit → resynthesise → encode) at 109
//! markers and m = 20, through `Pipeline::handle_datagram`; budget 2 µs a frame (issue 7).
//! Twice: the bare synthetic model (what `emoshift bench` measures), and the same model with
//! both glitch checks on (a speed limit and per-marker bounds, as a trained model has), set
//! loose enough that every sample passes, so the checks' full per-marker work is measured.

use std::net::SocketAddr;
use std::sync::Arc;

use criterion::{criterion_group, criterion_main, Criterion};
use daemon::engine::pipeline::{Pipeline, PipelineConfig};
use daemon::loopback::synthetic::{frame_into, labels_datagram, random_model};
use ica_core::model::{CaptureSettings, IcaModel, MarkerBounds};
use protocol::{encode_frame_into, FrameBuf};

fn bench_model(c: &mut Criterion, name: &str, model: IcaModel) {
    let model = Arc::new(model);
    let mut pipeline = Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default());
    let peer: SocketAddr = "127.0.0.1:9".parse().expect("literal address");
    let labels = labels_datagram(&model).expect("valid labels");
    pipeline.handle_datagram(peer, &labels, &mut |_| {});
    let mut xyz = vec![0.0; 109 * 3];
    let mut buf = FrameBuf::with_max_markers(109);
    let mut datagrams: Vec<Vec<u8>> = (0..120)
        .map(|f| {
            frame_into(&model, f, &mut xyz);
            buf.set_frame(0, 0, &xyz).expect("finite");
            let mut d = Vec::new();
            encode_frame_into(&buf, &mut d).expect("finite");
            d
        })
        .collect();
    let mut n: i32 = 0;
    c.bench_function(name, |b| {
        b.iter(|| {
            let d = &mut datagrams[n as usize % 120];
            // Frame numbers must increase or the stream drops the frame as stale.
            d[24..28].copy_from_slice(&n.to_be_bytes());
            n += 1;
            let mut out = 0;
            pipeline.handle_datagram(peer, d, &mut |e| out += e.compact.len());
            out
        })
    });
    let glitches = pipeline.counters.glitches;
    assert_eq!(
        glitches, 0,
        "{name}: the loose checks rejected {glitches} samples"
    );
}

fn whole_frame_path(c: &mut Criterion) {
    bench_model(
        c,
        "pipeline 109 markers m=20 compact",
        random_model(109, 20, 1),
    );
    let mut checked = random_model(109, 20, 1);
    let centre = checked
        .mean()
        .chunks_exact(3)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    let capture = CaptureSettings {
        max_speed_mm_s: Some(1e7),
        bounds: Some(MarkerBounds {
            centre,
            radius_mm: vec![1e4; 109],
        }),
        ..CaptureSettings::default()
    };
    checked
        .set_capture(capture)
        .expect("bounds for every marker");
    bench_model(
        c,
        "pipeline 109 markers m=20 compact, glitch checks",
        checked,
    );
}

criterion_group!(benches, whole_frame_path);
criterion_main!(benches);
