//! Shared pieces: a model on disk, an in-process daemon on ephemeral loopback ports, a frame
//! sender, receivers and a control client.

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::time::Duration;

use daemon::loopback::synthetic::{frame_into, random_model};
use daemon::serve::config::RawConfig;
use ica_core::model::IcaModel;
use protocol::{
    decode_frame_into, decode_reply, encode_control_into, encode_frame_into, encode_labels_into,
    messages, Address, Control, FrameBuf, Labels, Limits, Reply,
};
use tokio::net::UdpSocket;
use tokio_util::sync::CancellationToken;

pub const MARKERS: usize = 12;
pub const COMPONENTS: usize = 4;
/// How long a receiver waits for its first datagram.
const FIRST_WAIT: Duration = Duration::from_secs(5);

/// A model written to a temporary folder.
pub struct ModelFile {
    pub dir: tempfile::TempDir,
    pub path: PathBuf,
    pub model: IcaModel,
}

pub fn model_file(seed: u64) -> ModelFile {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("model.json");
    let model = random_model(MARKERS, COMPONENTS, seed);
    write_model(&model, &path);
    ModelFile { dir, path, model }
}

pub fn write_model(model: &IcaModel, path: &Path) {
    let file = std::fs::File::create(path).expect("writable temp dir");
    model
        .save(std::io::BufWriter::new(file))
        .expect("model saves");
}

/// An in-process daemon.
pub struct Daemon {
    pub frames: SocketAddr,
    pub control: SocketAddr,
    pub shutdown: CancellationToken,
    pub task: tokio::task::JoinHandle<anyhow::Result<()>>,
}

pub async fn start(model: &Path, send: Vec<String>) -> Daemon {
    let raw = RawConfig {
        listen: Some("127.0.0.1:0".into()),
        control: Some("127.0.0.1:0".into()),
        model: Some(model.to_path_buf()),
        send,
        // Room for a whole test burst: these tests check that no frame is lost.
        queue: Some(4096),
        ..RawConfig::default()
    };
    let bound = daemon::serve::bind(raw.validate().expect("valid config"))
        .await
        .expect("daemon binds");
    let (frames, control) = (
        bound.frame_addr().expect("bound"),
        bound.control_addr().expect("bound"),
    );
    let shutdown = CancellationToken::new();
    let task = tokio::spawn(bound.run(shutdown.clone()));
    Daemon {
        frames,
        control,
        shutdown,
        task,
    }
}

impl Daemon {
    pub async fn stop(self) {
        self.shutdown.cancel();
        tokio::time::timeout(Duration::from_secs(2), self.task)
            .await
            .expect("daemon stops within 2 s")
            .expect("daemon task")
            .expect("daemon ran cleanly");
    }
}

/// The frames of a synthetic take, model order.
pub fn take_frames(model: &IcaModel, n: usize) -> Vec<Vec<f32>> {
    (0..n)
        .map(|f| {
            let mut xyz = vec![0.0; MARKERS * 3];
            frame_into(model, f, &mut xyz);
            xyz
        })
        .collect()
}

/// A source: sends labels, then frames.
pub struct Source {
    pub sock: UdpSocket,
    pub to: SocketAddr,
    buf: FrameBuf,
    out: Vec<u8>,
}

impl Source {
    pub async fn new(to: SocketAddr, model: &IcaModel) -> Source {
        let sock = UdpSocket::bind("127.0.0.1:0").await.expect("bind");
        let mut out = Vec::new();
        let labels = Labels {
            layout_id: 0,
            names: model.labels().to_vec(),
        };
        encode_labels_into(&labels, &mut out).expect("labels");
        sock.send_to(&out, to).await.expect("send labels");
        Source {
            sock,
            to,
            buf: FrameBuf::with_max_markers(MARKERS),
            out,
        }
    }

    pub async fn frame(&mut self, n: i32, xyz: &[f32]) {
        self.buf.set_frame(n, i64::from(n), xyz).expect("finite");
        encode_frame_into(&self.buf, &mut self.out).expect("finite");
        self.sock.send_to(&self.out, self.to).await.expect("send");
        // Loopback is fast; a short pause every few frames keeps the socket buffers far from
        // full, so a lost frame can only be the daemon's doing.
        if n % 8 == 7 {
            tokio::time::sleep(Duration::from_millis(1)).await;
        }
    }

    pub async fn raw(&self, bytes: &[u8]) {
        self.sock.send_to(bytes, self.to).await.expect("send");
    }
}

/// A control client.
pub struct ControlClient {
    sock: UdpSocket,
    to: SocketAddr,
}

impl ControlClient {
    pub async fn new(to: SocketAddr) -> ControlClient {
        ControlClient {
            sock: UdpSocket::bind("127.0.0.1:0").await.expect("bind"),
            to,
        }
    }

    pub async fn send(&self, c: &Control) -> Reply {
        let mut out = Vec::new();
        encode_control_into(c, &mut out);
        self.sock.send_to(&out, self.to).await.expect("send");
        let mut buf = vec![0u8; 65_536];
        let n = tokio::time::timeout(Duration::from_secs(5), self.sock.recv(&mut buf))
            .await
            .expect("a reply within 5 s")
            .expect("recv");
        decode_reply(&buf[..n]).expect("a well-formed reply")
    }

    pub async fn status(&self, name: &str) -> i64 {
        match self.send(&Control::Status).await {
            Reply::Status(pairs) => pairs
                .iter()
                .find(|(k, _)| k == name)
                .map(|(_, v)| *v)
                .unwrap_or_else(|| panic!("no counter {name}")),
            other => panic!("expected a status, got {other:?}"),
        }
    }
}

/// A receiver subscribed through `/subscribe` (to its own port).
#[derive(Clone)]
pub struct Receiver {
    pub sock: std::sync::Arc<UdpSocket>,
}

impl Receiver {
    pub async fn subscribe(control: &ControlClient, profile: protocol::Profile) -> Receiver {
        let sock = UdpSocket::bind("127.0.0.1:0").await.expect("bind");
        let port = sock.local_addr().expect("bound").port();
        let reply = control.send(&Control::Subscribe { port, profile }).await;
        assert!(matches!(reply, Reply::Confirm(_)), "{reply:?}");
        Receiver {
            sock: std::sync::Arc::new(sock),
        }
    }

    /// Collects compact frames in the background (so the socket buffer never fills) until
    /// `quiet` passes without one after the first.
    pub fn spawn_frames(&self, quiet: Duration) -> tokio::task::JoinHandle<Vec<(i32, Vec<f32>)>> {
        let me = self.clone();
        tokio::spawn(async move { me.frames(quiet).await })
    }

    /// [`Receiver::spawn_frames`] for component frames.
    pub fn spawn_components(&self, quiet: Duration) -> tokio::task::JoinHandle<Vec<Vec<f32>>> {
        let me = self.clone();
        tokio::spawn(async move { me.components(quiet).await })
    }

    /// Compact frames (number, positions) until `quiet` passes without one.
    pub async fn frames(&self, quiet: Duration) -> Vec<(i32, Vec<f32>)> {
        let mut got = Vec::new();
        let mut buf = vec![0u8; 65_536];
        let mut frame = FrameBuf::with_max_markers(MARKERS);
        let mut wait = FIRST_WAIT;
        while let Ok(Ok(n)) = tokio::time::timeout(wait, self.sock.recv(&mut buf)).await {
            wait = quiet;
            for m in messages(&buf[..n], &Limits::default()).expect("well-formed output") {
                if Address::parse(m.address) == Some(Address::Frame) {
                    let h = decode_frame_into(m.bytes, &mut frame).expect("valid frame");
                    got.push((h.frame_number, frame.positions().to_vec()));
                }
            }
        }
        got
    }

    /// Component frames until `quiet` passes without one.
    pub async fn components(&self, quiet: Duration) -> Vec<Vec<f32>> {
        let mut got = Vec::new();
        let mut buf = vec![0u8; 65_536];
        let mut wait = FIRST_WAIT;
        while let Ok(Ok(n)) = tokio::time::timeout(wait, self.sock.recv(&mut buf)).await {
            wait = quiet;
            let mut u = vec![0.0; COMPONENTS];
            // A bundle when the model names components for VMC receivers, else one message.
            let msgs = protocol::messages(&buf[..n], &protocol::Limits::default()).expect("osc");
            for m in msgs {
                if protocol::Address::parse(m.address) == Some(protocol::Address::Components) {
                    let k = protocol::decode_components_into(m.bytes, &mut u).expect("components");
                    assert_eq!(k, COMPONENTS);
                    got.push(u.clone());
                }
            }
        }
        got
    }
}
