//! Issue 30 (ports): the daemon's input and output seams were rebuilt; what it sends must not
//! have changed. A take goes through `serve` with edits (a performer's default emotion, a
//! ramp, a translate, a gain, a target, a mix, bypass on and off, an amount), gaps, a
//! duplicate, an occluded marker and timecode, once over OSC and once from a NatNet server;
//! every datagram of each OSC profile (compact, flat-split, components), and the session
//! recording's files (edited and raw), must be byte for byte what the daemon sent before the
//! change.
//!
//! Nothing in the output varies per run: the source's capture times and timecodes are fixed
//! by the script (nothing is masked), each stream is named by a performer or a NatNet
//! markerset (not by the source's ephemeral port), and the take runs in lockstep (each frame
//! sent once the previous one came out, each control confirmed between two frames), so no
//! datagram is lost or reordered.
//!
//! The golden digests (`fixtures/regression_30.txt`: per datagram or file, its length and
//! FNV-1a 64 digest) were made from main at b9d4c93 by running this test with
//! `EMOSHIFT_BLESS=1`. Bless again only for a change that is meant to alter the bytes
//! (the numerics of projection or edit, the wire format), and say so in the commit.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use daemon::loopback::motive::{Motive, MotiveOptions};
use daemon::loopback::{self, synthetic};
use daemon::serve::config::{RawConfig, RawPerformer};
use ica_core::model::IcaModel;
use protocol::natnet::{FrameOfData, MarkersetDef, ModelDefs, NatNetVersion};
use protocol::{
    encode_frame_timed_into, messages, Address, CaptureClock, Control, FrameBuf, FrameTime, Limits,
    Profile, Smpte, TimecodeRate,
};
use tokio::net::UdpSocket;

const MARKERS: usize = 100;
const COMPONENTS: usize = 6;
const PROFILES: [Profile; 3] = [Profile::Compact, Profile::FlatSplit, Profile::Components];
/// How long a receiver waits for a frame it expects.
const WAIT: Duration = Duration::from_secs(5);
/// The quiet spell that ends a receiver's drain.
const QUIET: Duration = Duration::from_millis(300);

fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/regression_30.txt")
}

/// FNV-1a, 64 bits: a digest that needs no crate and never changes.
fn fnv64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// One line per datagram or file: `<what> <index> <length> <digest>`.
fn lines(what: &str, items: &[Vec<u8>]) -> Vec<String> {
    items
        .iter()
        .enumerate()
        .map(|(i, b)| format!("{what} {i} {} {:016x}", b.len(), fnv64(b)))
        .collect()
}

/// Three loopback sockets, one subscribed per profile.
struct Subscribers {
    sockets: Vec<UdpSocket>,
    got: Vec<Vec<Vec<u8>>>,
}

impl Subscribers {
    async fn new(control: &loopback::ControlClient) -> Subscribers {
        let mut sockets = Vec::new();
        for profile in PROFILES {
            let socket = daemon::serve::net::bind_receiver("127.0.0.1:0".parse().expect("addr"))
                .expect("a loopback socket");
            let port = socket.local_addr().expect("bound").port();
            let subscribe = Control::Subscribe {
                port,
                profile,
                performer: None,
                cookie: None,
            };
            control.confirm(&subscribe).await.expect("subscribed");
            sockets.push(socket);
        }
        Subscribers {
            got: vec![Vec::new(); sockets.len()],
            sockets,
        }
    }

    /// Reads the compact subscriber's datagrams until one carries frame `n`.
    async fn wait_frame(&mut self, n: i32) {
        let mut buf = vec![0u8; protocol::MAX_UDP_PAYLOAD];
        let deadline = Instant::now() + WAIT;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            let len = tokio::time::timeout(left, self.sockets[0].recv(&mut buf))
                .await
                .unwrap_or_else(|_| panic!("frame {n} did not come out within {WAIT:?}"))
                .expect("receive");
            let datagram = buf[..len].to_vec();
            let number = frame_number(&datagram);
            self.got[0].push(datagram);
            if number == Some(n) {
                return;
            }
        }
    }

    /// Drains every socket until a quiet spell; what each profile received.
    async fn finish(mut self) -> Vec<Vec<Vec<u8>>> {
        let mut buf = vec![0u8; protocol::MAX_UDP_PAYLOAD];
        for (socket, got) in self.sockets.iter().zip(&mut self.got) {
            while let Ok(r) = tokio::time::timeout(QUIET, socket.recv(&mut buf)).await {
                got.push(buf[..r.expect("receive")].to_vec());
            }
        }
        self.got
    }
}

/// How many of `datagrams` carry a message to `address`.
fn carrying(datagrams: &[Vec<u8>], address: Address) -> usize {
    datagrams
        .iter()
        .filter(|d| {
            messages(d, &Limits::default())
                .is_ok_and(|mut m| m.any(|m| Address::parse(m.address) == Some(address)))
        })
        .count()
}

/// The number of the compact frame a datagram carries.
fn frame_number(datagram: &[u8]) -> Option<i32> {
    let mut frame = FrameBuf::with_max_markers(MARKERS);
    messages(datagram, &Limits::default())
        .ok()?
        .filter(|m| Address::parse(m.address) == Some(Address::Frame))
        .find_map(|m| protocol::decode_frame_into(m.bytes, &mut frame).ok())
        .map(|h| h.frame_number)
}

fn model() -> (tempfile::TempDir, PathBuf, IcaModel) {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("model.json");
    let model = synthetic::random_space_model(MARKERS, COMPONENTS, 30);
    let file = std::fs::File::create(&path).expect("writable temp dir");
    model
        .save(std::io::BufWriter::new(file))
        .expect("model saves");
    (dir, path, model)
}

fn config(model: &Path) -> RawConfig {
    RawConfig {
        listen: Some("127.0.0.1:0".into()),
        control: Some("127.0.0.1:0".into()),
        model: Some(model.to_path_buf()),
        queue: Some(4096),
        // No renewal needed within the test.
        subscription_lease_s: Some(600.0),
        ..RawConfig::default()
    }
}

/// 29.97 DF timecode of frame `n` at 120 Hz, from just before a minute boundary.
fn timecode(n: usize) -> Smpte {
    let mut tc = Smpte::from_frame_count(1_790 + n as u64 / 4, TimecodeRate::DF_29_97);
    tc.subframe = n as u32 % 4;
    tc
}

/// What happens before frame `n` of the OSC take: an edit.
fn osc_edit(n: usize) -> Vec<Control> {
    match n {
        0 => vec![
            Control::Ramp(0.25),
            Control::Alpha {
                component: 1,
                value: 0.8,
            },
            Control::Gain {
                component: 3,
                gain: 1.4,
            },
        ],
        80 => vec![Control::Target("happy".into())],
        130 => vec![Control::Mix(vec![
            ("sad".into(), 1.0),
            ("angry".into(), 1.0),
        ])],
        170 => vec![Control::Bypass(true)],
        190 => vec![Control::Bypass(false), Control::Amount(1.0)],
        _ => vec![],
    }
}

/// Frame numbers of the OSC take: 0..240 with 100, 101 and 102 lost, and 150 sent twice.
fn osc_numbers() -> Vec<i32> {
    let mut numbers: Vec<i32> = (0..240).filter(|n| !(100..103).contains(n)).collect();
    let at = numbers.iter().position(|&n| n == 150).expect("150 is sent");
    numbers.insert(at + 1, 150);
    numbers
}

async fn osc_take() -> (Vec<Vec<Vec<u8>>>, Vec<Vec<u8>>) {
    let (dir, path, model) = model();
    let mut raw = config(&path);
    raw.performers = vec![RawPerformer {
        name: "alice".into(),
        emotion: Some("sad".into()),
        amount: Some(0.5),
        ..RawPerformer::default()
    }];
    let d = loopback::Daemon::start(raw.validate().expect("valid config"))
        .await
        .expect("daemon binds");
    let control = loopback::ControlClient::new(d.control)
        .await
        .expect("client");
    let mut subs = Subscribers::new(&control).await;
    let (edited, input) = (dir.path().join("edited.csv"), dir.path().join("raw.csv"));
    let start = Control::RecordStart {
        path: edited.display().to_string(),
        raw: Some(input.display().to_string()),
        overwrite: false,
    };
    control.confirm(&start).await.expect("recording");

    let source = std::net::UdpSocket::bind("127.0.0.1:0").expect("source socket");
    let labels = synthetic::labels_datagram(&model).expect("labels");
    source.send_to(&labels, d.frames).expect("send");
    let mut xyz = vec![0.0f32; MARKERS * 3];
    let mut frame = FrameBuf::with_max_markers(MARKERS);
    let mut datagram = Vec::new();
    let mut last = None;
    for n in osc_numbers() {
        let index = n as usize;
        if last != Some(n) {
            for c in osc_edit(index) {
                control.confirm(&c).await.expect("edit confirmed");
            }
        }
        synthetic::frame_into(&model, index, &mut xyz);
        frame
            .set_frame(n, 1_000_000 + i64::from(n) * 8_333, &xyz)
            .expect("finite");
        if (40..60).contains(&index) {
            frame.set_missing(3, true);
            frame.set_missing(57, true);
        }
        // The first half carries a UTC capture clock, then a source clock, then none.
        let time = match index {
            0..120 => FrameTime {
                timecode: Some(timecode(index)),
                irig: None,
                clock: CaptureClock::Utc,
            },
            120..200 => FrameTime {
                timecode: Some(timecode(index)),
                irig: None,
                clock: CaptureClock::Source,
            },
            _ => FrameTime::default(),
        };
        encode_frame_timed_into(&frame, &time, &mut datagram).expect("encodes");
        source.send_to(&datagram, d.frames).expect("send");
        if index == 200 {
            // The labels again, mid-take, as a source sends them every second.
            source.send_to(&labels, d.frames).expect("send");
        }
        if last != Some(n) {
            subs.wait_frame(n).await;
        }
        last = Some(n);
    }
    control
        .confirm(&Control::RecordStop)
        .await
        .expect("recording closed");
    let got = subs.finish().await;
    d.stop(Duration::from_secs(5)).await.expect("stops cleanly");
    let files = [edited, input]
        .iter()
        .map(|p| std::fs::read(p).expect("recorded"))
        .collect();
    (got, files)
}

async fn natnet_take() -> Vec<Vec<Vec<u8>>> {
    let (_dir, path, model) = model();
    let defs = ModelDefs {
        markersets: vec![MarkersetDef {
            name: "Face".into(),
            marker_names: model.labels().to_vec(),
        }],
        ..ModelDefs::default()
    };
    let mut server = Motive::start(MotiveOptions {
        command: "127.0.0.1:0".parse().expect("addr"),
        multicast: None,
        version: NatNetVersion::V3_0,
        defs,
        epoch: Instant::now(),
        rate_hz: 120.0,
    })
    .expect("the stand-in binds");
    let mut raw = config(&path);
    raw.natnet = Some(server.command_addr().to_string());
    raw.natnet_names = Some("marker".into());
    raw.natnet_timecode_rate = Some("29.97df".into());
    let d = loopback::Daemon::start(raw.validate().expect("valid config"))
        .await
        .expect("daemon binds");
    let control = loopback::ControlClient::new(d.control)
        .await
        .expect("client");
    wait_natnet(&control).await;
    let mut subs = Subscribers::new(&control).await;
    for c in [Control::Ramp(0.0), Control::Target("angry".into())] {
        control.confirm(&c).await.expect("edit confirmed");
    }
    let mut xyz = vec![0.0f32; MARKERS * 3];
    let mut f = FrameOfData::default();
    for n in 0..120usize {
        synthetic::frame_into(&model, n, &mut xyz);
        let mut metres: Vec<[f32; 3]> = xyz
            .chunks_exact(3)
            .map(|c| [c[0] / 1e3, c[1] / 1e3, c[2] / 1e3])
            .collect();
        if (30..40).contains(&n) {
            // Occluded: Motive sends it at the origin.
            metres[5] = [0.0; 3];
        }
        let tc = timecode(n);
        f.clear();
        f.frame_number = n as i32;
        f.push_markerset("Face", &metres);
        f.timecode = tc.packed();
        f.timecode_subframe = tc.subframe;
        f.camera_mid_exposure = 2_000_000 + n as u64 * 8_333;
        if n == 60 {
            control
                .confirm(&Control::Amount(0.4))
                .await
                .expect("edit confirmed");
        }
        server.send(&f).expect("encodes");
        subs.wait_frame(n as i32).await;
    }
    let got = subs.finish().await;
    d.stop(Duration::from_secs(5)).await.expect("stops cleanly");
    server.stop();
    got
}

async fn wait_natnet(control: &loopback::ControlClient) {
    for _ in 0..200 {
        let s = control.status().await.expect("status");
        if loopback::text(&s, "natnet/markersets").is_some_and(|m| m.contains("Face")) {
            return;
        }
        tokio::time::sleep(Duration::from_millis(25)).await;
    }
    panic!("the daemon never got the stand-in's model definitions");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn issue_30_each_osc_profile_and_the_recording_are_byte_for_byte_as_before() {
    let (osc, files) = osc_take().await;
    let natnet = natnet_take().await;
    // The take came through at all: every frame processed once, in every profile (flat-split
    // in two parts).
    for (take, got, frames) in [("osc", &osc, 237), ("natnet", &natnet, 120)] {
        let want = [
            (Address::Frame, frames),
            (Address::Part, 2 * frames),
            (Address::Components, frames),
        ];
        for ((address, n), datagrams) in want.into_iter().zip(got.iter()) {
            assert_eq!(
                carrying(datagrams, address),
                n,
                "{take}: {address:?} messages out"
            );
        }
    }
    let mut now = Vec::new();
    for (take, got) in [("osc", &osc), ("natnet", &natnet)] {
        for (profile, datagrams) in PROFILES.iter().zip(got.iter()) {
            now.extend(lines(&format!("{take}/{}", profile.as_str()), datagrams));
        }
    }
    now.extend(lines("osc/recording", &files));
    let now = now.join("\n") + "\n";
    if std::env::var_os("EMOSHIFT_BLESS").is_some() {
        std::fs::write(fixture(), &now).expect("fixture written");
        return;
    }
    let golden = std::fs::read_to_string(fixture()).expect("the golden fixture is in the repo");
    if let Some((i, (want, got))) = golden
        .lines()
        .zip(now.lines())
        .enumerate()
        .find(|(_, (a, b))| a != b)
    {
        panic!("datagram {i} differs from before the change: want `{want}`, got `{got}`");
    }
    assert_eq!(
        golden.lines().count(),
        now.lines().count(),
        "as many datagrams and files as before the change"
    );
}
