//! The live frame path allocates nothing once warm: 10,000 frames (109 markers, m = 20, some
//! markers missing, a live emotion edit gliding, every output profile encoded) as `serve`
//! runs them: the OSC intake (allow-list, demux) on the processing thread, and, for every other
//! frame, the processing queue the NatNet and QTM sources use (pooled buffers, shared labels,
//! the doorbell), `Pipeline::handle_frame`, the sinks: every OSC profile encoded, and the monitor page's feed
//! open (a 30 Hz snapshot of the stream published to the board). Then the same without a model
//! (issue 37: frames passed through unedited). Counted by allocation-counter's global
//! allocator (no `unsafe` here: the workspace forbids it).

use std::net::SocketAddr;
use std::sync::atomic::AtomicU64;
use std::sync::Arc;
use std::time::Instant;

use daemon::loopback::synthetic::{frame_into, random_model};
use daemon::serve::allow::AllowList;
use daemon::serve::monitor::Board;
use daemon::serve::queue::Queue;
use daemon::serve::sinks::osc::encode::EncodeOnly;
use daemon::serve::sources::osc::{OscDemux, OscIntake};
use daemon::serve::sources::{Answer, Arrival, InputCounters};
use daemon::serve::wake::Doorbell;
use engine::monitor::MonitorTap;
use engine::pipeline::{Pipeline, PipelineConfig};
use engine::{Needs, Processed, Sink};
use ica_core::model::IcaModel;
use protocol::{encode_frame_into, encode_labels_into, Control, FrameBuf, Labels};

const MARKERS: usize = 109;

/// Every profile encoded, then the monitor tap on the frame clock (every 4th frame at 120 Hz).
struct Outputs {
    encoded: EncodeOnly,
    tap: MonitorTap,
    board: Board,
    published: u64,
}

impl Sink for Outputs {
    fn needs(&self) -> Needs {
        self.encoded.needs()
    }

    fn handle_frame(&mut self, frame: &Processed<'_>) {
        self.encoded.handle_frame(frame);
        let now_us = frame.frame_number() as u64 * 8_333;
        if let Some(snap) = self.tap.handle_stream(now_us, frame.stream) {
            self.published += u64::from(self.board.publish(snap));
        }
    }
}

#[test]
fn the_frame_path_does_not_allocate() {
    let model = Arc::new(random_model(MARKERS, 20, 4));
    let mut p = Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default());
    for c in [
        Control::Target("happy".into()),
        Control::Amount(0.8),
        Control::Alpha {
            component: 3,
            value: 1.0,
        },
        Control::Gain {
            component: 5,
            gain: 1.2,
        },
    ] {
        p.handle_edit(&c).expect("valid edit");
    }
    ten_thousand_frames(p, &model, "edited");
    let passthrough = Pipeline::without_model(vec![], PipelineConfig::default());
    ten_thousand_frames(passthrough, &model, "passed through without a model");
}

/// 200 frames to warm up, then 10,000 counted, through `p` as `serve` runs them.
fn ten_thousand_frames(mut p: Pipeline, model: &IcaModel, what: &str) {
    let counters = Arc::new(InputCounters::named("osc"));
    let mut demux = OscDemux::new(1_000, Arc::clone(&counters));
    let poll = mio::Poll::new().expect("a poll instance");
    let waker = mio::Waker::new(poll.registry(), mio::Token(0)).expect("a waker");
    let bell = Doorbell::new(waker);
    let (queue, ends) = Queue::new(64, 1_000, Arc::new(AtomicU64::new(0)), bell);
    let answer = Arc::new(Answer::new(None));
    let allow = (AllowList::anyone(), Arc::new(AtomicU64::new(0)));
    let mut intake = OscIntake::new(allow, Arc::clone(&answer), Arc::clone(&counters), 1_000);
    let peer: SocketAddr = "127.0.0.1:7000".parse().expect("literal");
    let mut labels = Vec::new();
    let names = model.labels().to_vec();
    encode_labels_into(
        &Labels {
            layout_id: 2,
            names,
        },
        &mut labels,
    )
    .expect("labels");
    demux.handle_datagram(peer, &labels, &mut |_| {});
    intake.datagram(peer, &labels, Instant::now(), &mut |_, _| {});
    // 16 distinct frames, every fourth with three markers missing.
    let mut buf = FrameBuf::with_max_markers(MARKERS);
    let mut datagrams: Vec<Vec<u8>> = (0..16)
        .map(|f| {
            let mut xyz = vec![0.0f32; MARKERS * 3];
            frame_into(model, f, &mut xyz);
            if f % 4 == 0 {
                xyz[30..39].fill(f32::NAN);
            }
            buf.set_frame(0, 0, &xyz)
                .expect("finite or whole-marker NaN");
            let mut d = Vec::new();
            encode_frame_into(&buf, &mut d).expect("encodes");
            d
        })
        .collect();
    // The monitor page open: its tap copies every 4th frame and publishes it.
    let mut out = Outputs {
        encoded: EncodeOnly::all(1_000),
        tap: MonitorTap::new(30.0),
        board: Board::new(),
        published: 0,
    };
    out.board.set_viewers(1);
    let mut run = |p: &mut Pipeline, out: &mut Outputs, from: i32, count: i32| {
        for n in from..from + count {
            let d = &mut datagrams[n as usize % 16];
            // frame number after "/mocap/frame\0\0\0\0" and ",ihbb\0\0\0"
            d[24..28].copy_from_slice(&n.to_be_bytes());
            let received = Instant::now();
            if n % 2 == 0 {
                // The processing thread reads the frame socket: the intake, then the engine.
                intake.datagram(peer, d, received, &mut |frame, _| {
                    p.handle_frame(frame, out)
                });
                continue;
            }
            // A queued source's task: decoded, then copied into the queue.
            demux.handle_datagram(peer, d, &mut |frame| {
                let arrival = Arrival {
                    received,
                    captured: None,
                    answer: Some(Arc::clone(&answer)),
                    announced_rate_hz: None,
                };
                queue.push(frame, &arrival);
            });
            // The processing thread: off the queue, through the engine, the buffer back.
            let item = ends.frames.try_recv().expect("queued");
            p.handle_frame(&item.source(), out);
            let _ = ends.free.try_send(item.into_buffer());
        }
    };
    run(&mut p, &mut out, 0, 200);
    let info = allocation_counter::measure(|| run(&mut p, &mut out, 200, 10_000));
    assert_eq!(p.counters.frames_out, 10_200, "every frame processed");
    assert_eq!(counters.snapshot().frames_in, 10_200, "every frame decoded");
    assert!(
        out.published >= 10_200 / 5,
        "the tap published {} snapshots",
        out.published
    );
    assert!(
        out.encoded.bytes > 10_200 * 1_000 && out.encoded.errors == 0,
        "every profile encoded"
    );
    assert_eq!(
        info.count_total, 0,
        "allocations in 10,000 frames {what}: {info:?}"
    );
}
