use protocol::{
    encode_frame_into, encode_frame_timed_into, encode_labels_into, CaptureClock, Labels, Smpte,
    TimecodeRate,
};

use super::*;

const MARKERS: usize = 4;

fn peer(port: u16) -> SocketAddr {
    SocketAddr::from(([127, 0, 0, 1], port))
}

fn labels(names: &[&str], layout_id: i32) -> Vec<u8> {
    let labels = Labels {
        layout_id,
        names: names.iter().map(|n| n.to_string()).collect(),
    };
    let mut out = Vec::new();
    encode_labels_into(&labels, &mut out).expect("valid labels");
    out
}

fn frame(n: i32, time: Option<FrameTime>) -> Vec<u8> {
    let mut buf = FrameBuf::with_max_markers(MARKERS);
    buf.set_frame(n, 99, &[1.0; MARKERS * 3]).expect("finite");
    let mut out = Vec::new();
    match time {
        Some(t) => encode_frame_timed_into(&buf, &t, &mut out),
        None => encode_frame_into(&buf, &mut out),
    }
    .expect("finite");
    out
}

/// Each frame out: (source, layout id, frame number, labels, time).
type Out = Vec<(SocketAddr, i32, i32, Vec<String>, FrameTime)>;

fn feed(d: &mut OscDemux, from: SocketAddr, datagram: &[u8], got: &mut Out) {
    d.handle_datagram(from, datagram, &mut |f| {
        got.push((
            f.key.source,
            f.key.layout_id,
            f.frame_number(),
            f.labels.to_vec(),
            f.time,
        ));
    });
}

#[test]
fn frames_are_bound_to_their_sources_latest_labels_and_bad_packets_counted() {
    let counters = Arc::new(InputCounters::named("osc"));
    let mut d = OscDemux::new(100, Arc::clone(&counters));
    let mut got = Vec::new();
    feed(&mut d, peer(1), &frame(0, None), &mut got);
    feed(&mut d, peer(1), &labels(&["a", "b", "c", "d"], 7), &mut got);
    feed(&mut d, peer(1), &frame(1, None), &mut got);
    feed(&mut d, peer(1), &[1, 2, 3], &mut got);
    feed(&mut d, peer(2), &frame(2, None), &mut got);
    feed(&mut d, peer(1), &labels(&["w", "x", "y", "z"], 8), &mut got);
    feed(&mut d, peer(1), &frame(3, None), &mut got);
    let names = |s: &[&str]| s.iter().map(|n| n.to_string()).collect::<Vec<_>>();
    assert_eq!(
        got.iter()
            .map(|g| (g.0, g.1, g.2, g.3.clone()))
            .collect::<Vec<_>>(),
        [
            (peer(1), 7, 1, names(&["a", "b", "c", "d"])),
            (peer(1), 8, 3, names(&["w", "x", "y", "z"])),
        ]
    );
    let c = counters.snapshot();
    assert_eq!((c.frames_in, c.dropped_no_layout), (4, 2));
    assert_eq!((c.labels_in, c.bad_total()), (2, 1));
}

/// Issue 16: a source's `/mocap/timecode` is the time of the frame in its datagram; a frame
/// without one has none.
#[test]
fn the_timecode_in_a_datagram_is_its_frames_time() {
    let mut d = OscDemux::new(100, Arc::new(InputCounters::default()));
    let time = FrameTime {
        timecode: Some(Smpte::from_frame_count(1_800, TimecodeRate::DF_29_97)),
        irig: None,
        clock: CaptureClock::Utc,
    };
    let mut got = Vec::new();
    feed(&mut d, peer(1), &labels(&["a", "b", "c", "d"], 0), &mut got);
    feed(&mut d, peer(1), &frame(1, Some(time)), &mut got);
    feed(&mut d, peer(1), &frame(2, None), &mut got);
    assert_eq!(got[0].4, time);
    assert_eq!(got[1].4, FrameTime::default());
    assert_eq!(
        time.timecode.map(|t| t.to_string()).as_deref(),
        Some("00:01:00;02.0")
    );
}

/// A layout naming a marker twice is refused with a reason; past the source cap a new source
/// hears why, and once the others went quiet it is taken.
#[test]
fn refused_labels_are_told_and_quiet_sources_make_room() {
    let counters = Arc::new(InputCounters::default());
    let mut d = OscDemux::new(100, Arc::clone(&counters));
    let mut got = Vec::new();
    feed(&mut d, peer(1), &labels(&["a", "b", "a", "d"], 0), &mut got);
    let why = d.poll_refusal().expect("told why");
    assert_eq!(why.to, peer(1));
    assert!(why.why.contains("argument 3 is named twice"), "{}", why.why);
    let names = ["a", "b", "c", "d"];
    for i in 0..MAX_SOURCES as u16 {
        feed(&mut d, peer(100 + i), &labels(&names, 0), &mut got);
    }
    assert!(d.poll_refusal().is_none());
    let late = peer(100 + MAX_SOURCES as u16);
    feed(&mut d, late, &labels(&names, 0), &mut got);
    let why = d.poll_refusal().expect("told why");
    assert!(why.why.contains("64 sources"), "{}", why.why);
    feed(&mut d, late, &frame(1, None), &mut got);
    assert!(got.is_empty(), "no layout yet");
    assert_eq!(counters.snapshot().labels_refused, 2);
    // Source 100 keeps sending; the others are silent through the sweeps.
    for sweep in 0..QUIET_SWEEPS {
        assert!(d.forget_quiet_sources().is_empty(), "sweep {sweep}");
        feed(&mut d, peer(100), &frame(sweep as i32, None), &mut got);
    }
    assert_eq!(d.forget_quiet_sources().len(), MAX_SOURCES - 1);
    feed(&mut d, late, &labels(&names, 0), &mut got);
    feed(&mut d, late, &frame(1, None), &mut got);
    assert_eq!(got.last().map(|g| g.0), Some(late), "taken now");
}
