//! The whole live frame path (decode → map → project → edit → resynthesise → encode) at 109
//! markers and m = 20, as the processing thread runs it: the OSC demux, `Pipeline::handle_frame`,
//! the compact profile encoded; budget 2 µs a frame (issue 7).
//! Twice: the bare synthetic model (what `emoshift bench` measures), and the same model with
//! both glitch checks on (a speed limit and per-marker bounds, as a trained model has), set
//! loose enough that every sample passes, so the checks' full per-marker work is measured. And
//! the bare model again with the monitor page open (issue 17): after each frame the processing
//! thread's tap, at 120 Hz on a 30 Hz schedule, so every 4th frame is copied and published to
//! the board, as `serve` does while a page is open; against the first line, its cost per frame.
//! And the bare model while `/record/start` records the edited stream and the raw input to C3D
//! (issue 36): the processing thread's share of a crash-safe recording (each frame encoded and
//! handed to the file's own thread; the writes, syncs and header counts happen there). Its
//! files go to /dev/shm where there is one, each sample's deleted after it, so the bench
//! measures the frame path rather than the disk. And without a model (issue 37: `serve`
//! started before the performer's model exists): the same frames passed through unedited.

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use criterion::{criterion_group, criterion_main, Criterion};
use daemon::serve::monitor::Board;
use daemon::serve::sinks::osc::encode::{EncodeOnly, Profiles};
use daemon::serve::sinks::recording::Recorder;
use daemon::serve::sources::osc::OscDemux;
use daemon::serve::sources::InputCounters;
use engine::monitor::MonitorTap;
use engine::pipeline::{Pipeline, PipelineConfig};
use engine::synthetic::{frame_into, labels_datagram, random_model};
use engine::{Needs, Processed, Sink};
use ica_core::model::{CaptureSettings, IcaModel, MarkerBounds};
use protocol::{encode_frame_into, FrameBuf, Profile};

/// The compact profile encoded, then, with the monitor page open, the feed's tap on the
/// frame clock (120 Hz frames, a 30 Hz schedule: every 4th frame copied and published), as
/// `serve`'s feed does on the wall clock.
struct Outputs {
    compact: EncodeOnly,
    tap: Option<(MonitorTap, Arc<Board>)>,
    recorder: Recorder,
}

impl Sink for Outputs {
    fn needs(&self) -> Needs {
        self.compact.needs().or(self.recorder.needs())
    }

    fn handle_frame(&mut self, frame: &Processed<'_>) {
        self.compact.handle_frame(frame);
        self.recorder.handle_frame(frame);
        if let Some((tap, board)) = &mut self.tap {
            let now_us = frame.frame_number() as u64 * 8_333;
            if board.watched() {
                if let Some(snap) = tap.handle_stream(now_us, frame.stream) {
                    board.publish(snap);
                }
            }
        }
    }
}

/// What runs beside the compact encoding.
#[derive(Clone, Copy, PartialEq)]
enum Beside {
    Nothing,
    MonitorPage,
    Recording,
    /// No model: the pipeline passes the frames through.
    NoModel,
}

/// Where a recording bench writes: memory where the system has a tmpfs.
fn scratch() -> tempfile::TempDir {
    let shm = Path::new("/dev/shm");
    let builder = tempfile::Builder::new();
    let dir = if shm.is_dir() {
        builder.tempdir_in(shm)
    } else {
        builder.tempdir()
    };
    dir.expect("a scratch folder")
}

fn bench_model(c: &mut Criterion, name: &str, model: IcaModel, beside: Beside) {
    let monitor = beside == Beside::MonitorPage;
    let model = Arc::new(model);
    let mut pipeline = match beside {
        Beside::NoModel => Pipeline::without_model(vec![], PipelineConfig::default()),
        _ => Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default()),
    };
    let mut demux = OscDemux::new(109, Arc::new(InputCounters::named("osc")));
    let peer: SocketAddr = "127.0.0.1:9".parse().expect("literal address");
    let board = Arc::new(Board::new());
    board.set_viewers(1);
    let mut outputs = Outputs {
        compact: EncodeOnly::new(Profiles::default().with(Profile::Compact), 109),
        tap: monitor.then(|| (MonitorTap::new(30.0), Arc::clone(&board))),
        recorder: Recorder::new(),
    };
    let labels = labels_datagram(&model).expect("valid labels");
    demux.handle_datagram(peer, &labels, &mut |_| {});
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
    let mut frame = |outputs: &mut Outputs| {
        let d = &mut datagrams[n as usize % 120];
        // Frame numbers must increase or the stream drops the frame as stale.
        d[24..28].copy_from_slice(&n.to_be_bytes());
        n += 1;
        demux.handle_datagram(peer, d, &mut |f| pipeline.handle_frame(f, outputs));
        outputs.compact.bytes
    };
    if beside == Beside::Recording {
        // Each sample records to new files (edited and raw C3D), closed and deleted after it:
        // a sample's frames are timed, the start and the close are not.
        c.bench_function(name, |b| {
            b.iter_custom(|iters| {
                let dir = scratch();
                let file = |name: &str| -> PathBuf { dir.path().join(name) };
                let raw = file("raw.c3d");
                outputs
                    .recorder
                    .start_at(&file("edited.c3d"), Some(&raw))
                    .expect("a recording starts");
                let start = Instant::now();
                for _ in 0..iters {
                    criterion::black_box(frame(&mut outputs));
                }
                let took = start.elapsed();
                assert!(outputs.recorder.error().is_none(), "the recording stopped");
                std::mem::take(&mut outputs.recorder).finish();
                took
            })
        });
    } else {
        c.bench_function(name, |b| b.iter(|| frame(&mut outputs)));
    }
    let mut tap = MonitorTap::new(30.0);
    if monitor {
        // The tap's own work, every call due: one snapshot copied and published.
        let key = pipeline.stream_status()[0].key;
        let stream = pipeline.stream(&key).expect("the stream");
        let mut now_us = 0u64;
        c.bench_function("monitor tap: one snapshot, 109 markers m=20", |b| {
            b.iter(|| {
                now_us += 40_000;
                tap.handle_stream(now_us, stream).map(|s| board.publish(s))
            })
        });
    }
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
        Beside::Nothing,
    );
    bench_model(
        c,
        "pipeline 109 markers compact, no model (passthrough)",
        random_model(109, 20, 1),
        Beside::NoModel,
    );
    bench_model(
        c,
        "pipeline 109 markers m=20 compact, monitor page open",
        random_model(109, 20, 1),
        Beside::MonitorPage,
    );
    bench_model(
        c,
        "pipeline 109 markers m=20 compact, recording edited + raw C3D",
        random_model(109, 20, 1),
        Beside::Recording,
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
        Beside::Nothing,
    );
}

criterion_group!(benches, whole_frame_path);
criterion_main!(benches);
