//! Issue 16, NatNet in: a Motive stand-in on loopback (multicast with TTL 0, or unicast)
//! streaming into `serve`. A face over NatNet comes out edited exactly as over OSC, none lost,
//! with its drop-frame timecode; the server restarting costs only the frames sent while it
//! was down; `/status` tells the session and the latency from mid-exposure.

use std::net::SocketAddr;
use std::time::{Duration, Instant};

use daemon::loopback::motive::{Motive, MotiveOptions};
use daemon::loopback::{self, ControlClient, Receiver};
use daemon::serve::config::RawConfig;
use protocol::natnet::{FrameOfData, MarkersetDef, ModelDefs, NatNetVersion};
use protocol::{CaptureClock, FrameBuf, FrameTime, Profile, Smpte, TimecodeRate};

use super::support::*;

const QUIET: Duration = Duration::from_millis(600);
const PERIOD: Duration = Duration::from_micros(8_333);

/// A free loopback port (bound, then released).
/// A stand-in describing one markerset "Face" with the model's marker names.
pub(super) fn motive(m: &ModelFile, command: SocketAddr, multicast: Option<SocketAddr>) -> Motive {
    let defs = ModelDefs {
        markersets: vec![MarkersetDef {
            name: "Face".into(),
            marker_names: m.model.labels().to_vec(),
        }],
        ..ModelDefs::default()
    };
    Motive::start(MotiveOptions {
        command,
        multicast,
        version: NatNetVersion::V3_0,
        defs,
        epoch: Instant::now(),
        rate_hz: 120.0,
    })
    .expect("the stand-in binds")
}

/// A daemon taking frames from `server` (markers named bare, 29.97 DF timecode).
async fn daemon(m: &ModelFile, server: SocketAddr) -> loopback::Daemon {
    let raw = RawConfig {
        listen: Some("127.0.0.1:0".into()),
        control: Some("127.0.0.1:0".into()),
        model: Some(m.path.clone()),
        queue: Some(4096),
        natnet: Some(server.to_string()),
        natnet_names: Some("marker".into()),
        natnet_timecode_rate: Some("29.97df".into()),
        ..RawConfig::default()
    };
    loopback::Daemon::start(raw.validate().expect("valid config"))
        .await
        .expect("daemon binds")
}

/// Frame `n` in metres (what NatNet carries) and its 29.97 DF timecode at 120 Hz, starting
/// just before a minute boundary (00:00:59;29 then 00:01:00;02).
fn frame(m: &ModelFile, n: usize) -> (Vec<[f32; 3]>, Smpte) {
    let mm = take_frames(&m.model, n + 1).pop().expect("a frame");
    let metres = mm
        .chunks_exact(3)
        .map(|c| [c[0] / 1e3, c[1] / 1e3, c[2] / 1e3])
        .collect();
    let mut tc = Smpte::from_frame_count(1_790 + n as u64 / 4, TimecodeRate::DF_29_97);
    tc.subframe = n as u32 % 4;
    (metres, tc)
}

/// Streams frames `range` at 120 Hz from the stand-in.
pub(super) async fn stream(m: &ModelFile, server: &mut Motive, range: std::ops::Range<usize>) {
    let mut tick = tokio::time::interval(PERIOD);
    let mut f = FrameOfData::default();
    for n in range {
        tick.tick().await;
        let (metres, tc) = frame(m, n);
        f.clear();
        f.frame_number = n as i32;
        f.push_markerset("Face", &metres);
        f.timecode = tc.packed();
        f.timecode_subframe = tc.subframe;
        f.camera_mid_exposure = server.ticks(Instant::now());
        server.send(&f).expect("encodes");
    }
}

type Got = Vec<(i32, Vec<f32>, Option<FrameTime>)>;

fn collect(r: &Receiver) -> tokio::task::JoinHandle<Got> {
    let c = r.collect(Some(QUIET), Vec::new(), |got: &mut Got, r| {
        if let Some((h, f)) = r.frame {
            got.push((h.frame_number, f.positions().to_vec(), r.time));
        }
    });
    tokio::spawn(async move { c.finish().await.expect("receiver") })
}

async fn wait_connected(control: &ControlClient) {
    for _ in 0..100 {
        let s = control.status().await.expect("status");
        if loopback::text(&s, "natnet/markersets").is_some_and(|m| m.contains("Face")) {
            return;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    panic!("the daemon never got the stand-in's model definitions");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_face_over_natnet_comes_out_as_over_osc_none_lost_timecode_intact() {
    let m = model_file(31);
    let group: SocketAddr = format!("239.255.42.99:{}", free_port())
        .parse()
        .expect("addr");
    let mut server = motive(&m, "127.0.0.1:0".parse().expect("addr"), Some(group));
    let d = daemon(&m, server.command_addr()).await;
    let control = ControlClient::new(d.control).await.expect("client");
    wait_connected(&control).await;
    let natnet_rx = Receiver::subscribe(&control, Profile::Compact)
        .await
        .expect("sub");
    let natnet_got = collect(&natnet_rx);
    stream(&m, &mut server, 0..240).await;
    let natnet_got = natnet_got.await.expect("receiver");
    // The same take over OSC into a second daemon, with the same timecode.
    let d2 = daemon_osc(&m).await;
    let control2 = ControlClient::new(d2.control).await.expect("client");
    let osc_rx = Receiver::subscribe(&control2, Profile::Compact)
        .await
        .expect("sub");
    let osc_got = collect(&osc_rx);
    send_osc(&m, d2.frames, 0..240).await;
    let osc_got = osc_got.await.expect("receiver");
    assert_eq!(natnet_got.len(), 240, "none lost at 120 Hz over NatNet");
    assert_eq!(osc_got.len(), 240, "none lost over OSC");
    for (a, b) in natnet_got.iter().zip(&osc_got) {
        assert_eq!((a.0, &a.1), (b.0, &b.1), "frame {} differs", a.0);
        let (_, tc) = frame(&m, a.0 as usize);
        assert_eq!(a.2.and_then(|t| t.timecode), Some(tc), "frame {}", a.0);
        assert_eq!(b.2.and_then(|t| t.timecode), Some(tc), "frame {}", b.0);
    }
    let tcs: Vec<String> = natnet_got[36..40]
        .iter()
        .filter_map(|g| Some(g.2?.timecode?.to_string()))
        .collect();
    assert_eq!(
        tcs,
        [
            "00:00:59;29.0",
            "00:00:59;29.1",
            "00:00:59;29.2",
            "00:00:59;29.3"
        ]
    );
    assert_eq!(
        natnet_got[40]
            .2
            .and_then(|t| t.timecode)
            .map(|t| t.to_string())
            .as_deref(),
        Some("00:01:00;02.0"),
        "drop-frame: ;00 and ;01 do not exist"
    );
    let status = control.status().await.expect("status");
    let get = |k: &str| loopback::counter(&status, k).unwrap_or(-1);
    assert_eq!(get("natnet/connected"), 1);
    assert_eq!(get("frames_out"), 240);
    assert!(
        get("stream/0/latency_p50_us") > 0,
        "latency from mid-exposure is measured"
    );
    assert_eq!(loopback::text(&status, "stream/0/name"), Some("Face"));
    assert_eq!(
        loopback::text(&status, "natnet/announced_rate_hz"),
        Some("120.000")
    );
    d.stop(Duration::from_secs(2)).await.expect("stops");
    d2.stop(Duration::from_secs(2)).await.expect("stops");
    server.stop();
}

async fn daemon_osc(m: &ModelFile) -> loopback::Daemon {
    let raw = RawConfig {
        listen: Some("127.0.0.1:0".into()),
        control: Some("127.0.0.1:0".into()),
        model: Some(m.path.clone()),
        queue: Some(4096),
        ..RawConfig::default()
    };
    loopback::Daemon::start(raw.validate().expect("valid config"))
        .await
        .expect("daemon binds")
}

/// The same frames over OSC, in millimetres as the daemon computes them from metres, each in
/// a bundle with its `/mocap/timecode`.
pub(super) async fn send_osc(m: &ModelFile, to: SocketAddr, range: std::ops::Range<usize>) {
    let labels = protocol::Labels {
        layout_id: 0,
        names: m.model.labels().to_vec(),
    };
    let mut source = loopback::Source::on_loopback(&labels, to).expect("source");
    source.send_labels();
    let mut buf = FrameBuf::with_max_markers(MARKERS);
    let mut bytes = Vec::new();
    let mut tick = tokio::time::interval(PERIOD);
    for n in range {
        tick.tick().await;
        let (metres, tc) = frame(m, n);
        let mm: Vec<f32> = metres.iter().flatten().map(|v| v * 1000.0).collect();
        buf.set_frame(n as i32, 0, &mm).expect("finite");
        let time = FrameTime {
            timecode: Some(tc),
            irig: None,
            clock: CaptureClock::Source,
        };
        protocol::encode_frame_timed_into(&buf, &time, &mut bytes).expect("finite");
        source.send_raw(&bytes);
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_server_restart_costs_only_the_frames_sent_while_it_was_down() {
    let m = model_file(32);
    let command: SocketAddr = format!("127.0.0.1:{}", free_port()).parse().expect("addr");
    let group: SocketAddr = format!("239.255.42.99:{}", free_port())
        .parse()
        .expect("addr");
    let mut server = motive(&m, command, Some(group));
    let d = daemon(&m, command).await;
    let control = ControlClient::new(d.control).await.expect("client");
    wait_connected(&control).await;
    let rx = Receiver::subscribe(&control, Profile::Compact)
        .await
        .expect("sub");
    let got = rx.collect(
        Some(Duration::from_secs(6)),
        Vec::new(),
        |got: &mut Vec<i32>, r| {
            if let Some((h, _)) = r.frame {
                got.push(h.frame_number);
            }
        },
    );
    stream(&m, &mut server, 0..120).await;
    server.stop();
    // Down past the client's 3 s silence timeout: it notices and reconnects.
    tokio::time::sleep(Duration::from_millis(3_600)).await;
    let mut server = motive(&m, command, Some(group));
    stream(&m, &mut server, 120..240).await;
    tokio::time::sleep(Duration::from_millis(300)).await;
    let status = control.status().await.expect("status");
    let got = got.stop().await.expect("receiver");
    let expected: Vec<i32> = (0..240).collect();
    assert_eq!(
        got, expected,
        "every frame the server sent while up came through"
    );
    let get = |k: &str| loopback::counter(&status, k).unwrap_or(-1);
    assert!(get("natnet/disconnects") >= 1, "the restart was noticed");
    assert!(get("natnet/connects") >= 2, "and the session reconnected");
    assert_eq!(get("natnet/connected"), 1);
    d.stop(Duration::from_secs(2)).await.expect("stops");
    server.stop();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn unicast_frames_come_to_the_client_that_connected() {
    let m = model_file(33);
    let mut server = motive(&m, "127.0.0.1:0".parse().expect("addr"), None);
    let d = daemon(&m, server.command_addr()).await;
    let control = ControlClient::new(d.control).await.expect("client");
    wait_connected(&control).await;
    assert_eq!(server.clients(), 1);
    let rx = Receiver::subscribe(&control, Profile::Compact)
        .await
        .expect("sub");
    let got = collect(&rx);
    stream(&m, &mut server, 0..60).await;
    let got = got.await.expect("receiver");
    assert_eq!(got.len(), 60);
    let status = control.status().await.expect("status");
    assert_eq!(
        loopback::text(&status, "natnet/data"),
        Some("the command socket (unicast)")
    );
    d.stop(Duration::from_secs(2)).await.expect("stops");
    server.stop();
}

/// `emoshift record --natnet`: the markerset's frames land in a C3D with the first frame's
/// drop-frame timecode and the server's announced rate, complete after Ctrl-C (SIGINT).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn record_from_natnet_is_complete_after_ctrl_c_with_its_timecode() {
    use std::process::{Command, Stdio};
    let m = model_file(34);
    let group: SocketAddr = format!("239.255.42.99:{}", free_port())
        .parse()
        .expect("addr");
    let mut server = motive(&m, "127.0.0.1:0".parse().expect("addr"), Some(group));
    let out = m.dir.path().join("face.c3d");
    let child = Command::new(env!("CARGO_BIN_EXE_emoshift-e2e"))
        .args(["record", "--natnet", &server.command_addr().to_string()])
        .args([
            "--natnet-names",
            "marker",
            "--natnet-timecode-rate",
            "29.97df",
        ])
        .arg("--out")
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("the binary starts");
    for _ in 0..100 {
        if server.clients() > 0 {
            break;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    // Time for the model definitions and the frame rate to come back.
    tokio::time::sleep(Duration::from_millis(500)).await;
    stream(&m, &mut server, 0..120).await;
    tokio::time::sleep(Duration::from_millis(200)).await;
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(kill.success());
    let done = tokio::task::spawn_blocking(move || child.wait_with_output())
        .await
        .expect("join")
        .expect("the child ends");
    assert!(done.status.success(), "{:?}", done.status);
    let printed = String::from_utf8_lossy(&done.stdout).to_string();
    assert!(printed.contains("120 frames of Face"), "{printed}");
    assert!(printed.contains("announced 120"), "{printed}");
    let take = replay::load(&out).expect("a complete C3D");
    assert_eq!((take.n_frames(), take.rate_hz), (120, 120.0));
    assert_eq!(take.labels, m.model.labels());
    let (metres, tc) = frame(&m, 0);
    let back = replay::c3d::read_time(&std::fs::read(&out).expect("read")).expect("params");
    assert_eq!(back.timecode, Some(tc));
    let want: Vec<f32> = metres.iter().flatten().map(|v| v * 1000.0).collect();
    assert_eq!(take.frame(0), want.as_slice());
    server.stop();
}

/// `emoshift record --listen` stops by itself after `--frames`, says so when nothing arrives,
/// and writes the OSC source's timecode into a CSV column.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn record_from_osc_stops_after_its_frames_and_says_when_nothing_arrives() {
    use std::process::{Command, Stdio};
    let m = model_file(35);
    let port = free_port();
    let out = m.dir.path().join("take.csv");
    let child = Command::new(env!("CARGO_BIN_EXE_emoshift-e2e"))
        .args(["record", "--listen", &format!("127.0.0.1:{port}")])
        .args(["--frames", "48", "--out"])
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary starts");
    // Silence first: the quiet line comes after 3 s.
    tokio::time::sleep(Duration::from_millis(3_400)).await;
    let to: SocketAddr = format!("127.0.0.1:{port}").parse().expect("addr");
    send_osc(&m, to, 0..60).await;
    let done = tokio::task::spawn_blocking(move || child.wait_with_output())
        .await
        .expect("join")
        .expect("the child ends by itself after 48 frames");
    assert!(done.status.success());
    let err = String::from_utf8_lossy(&done.stderr);
    assert!(err.contains("nothing has arrived on"), "{err}");
    let text = std::fs::read_to_string(&out).expect("written");
    let rows: Vec<&str> = text.lines().skip(2).collect();
    assert_eq!(rows.len(), 48);
    assert!(text
        .lines()
        .nth(1)
        .expect("header")
        .starts_with("frame,time,timecode,"));
    let (_, tc) = frame(&m, 40);
    assert_eq!(rows[40].split(',').nth(2), Some(tc.to_string().as_str()));
    assert_eq!(replay::load(&out).expect("loads").n_frames(), 48);
}
