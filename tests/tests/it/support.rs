//! Shared pieces: a model on disk, and the loopback harness (daemon, source, receivers, control
//! client) behind the small blocking-free API these tests were written against.

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::time::Duration;

use std::sync::Mutex;

use daemon::loopback;
use daemon::loopback::synthetic::{frame_into, random_model};
use daemon::serve::config::RawConfig;
use ica_core::model::IcaModel;
use protocol::{Control, Labels, Reply};

pub const MARKERS: usize = 12;
pub const COMPONENTS: usize = 4;

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
    inner: loopback::Daemon,
}

pub async fn start(model: &Path, send: Vec<String>) -> Daemon {
    start_on(Some(model), send).await
}

/// [`start`], with no model when `model` is `None` (frames pass through unedited).
pub async fn start_on(model: Option<&Path>, send: Vec<String>) -> Daemon {
    let raw = RawConfig {
        listen: Some("127.0.0.1:0".into()),
        control: Some("127.0.0.1:0".into()),
        model: model.map(Path::to_path_buf),
        send,
        // Room for a whole test burst: these tests check that no frame is lost.
        queue: Some(4096),
        ..RawConfig::default()
    };
    let inner = loopback::Daemon::start(raw.validate().expect("valid config"))
        .await
        .expect("daemon binds");
    Daemon {
        frames: inner.frames,
        control: inner.control,
        inner,
    }
}

impl Daemon {
    pub async fn stop(self) {
        self.inner
            .stop(Duration::from_secs(2))
            .await
            .expect("daemon stops within 2 s and ran cleanly");
    }
}

/// A UDP port free on loopback now (a child process binds it next).
pub fn free_port() -> u16 {
    std::net::UdpSocket::bind("127.0.0.1:0")
        .and_then(|s| s.local_addr())
        .expect("an ephemeral port")
        .port()
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
pub struct Source(Mutex<loopback::Source>);

impl Source {
    pub async fn new(to: SocketAddr, model: &IcaModel) -> Source {
        let labels = Labels {
            layout_id: 0,
            names: model.labels().to_vec(),
        };
        Source(Mutex::new(
            loopback::Source::on_loopback(&labels, to).expect("a loopback source"),
        ))
    }

    pub async fn frame(&mut self, n: i32, xyz: &[f32]) {
        self.0
            .get_mut()
            .expect("source")
            .send_frame(n, i64::from(n), xyz, &[])
            .expect("finite");
        // Loopback is fast; a short pause every few frames keeps the socket buffers far from
        // full, so a lost frame can only be the daemon's doing.
        if n % 8 == 7 {
            tokio::time::sleep(Duration::from_millis(1)).await;
        }
    }

    pub async fn raw(&self, bytes: &[u8]) {
        self.0.lock().expect("source").send_raw(bytes);
    }
}

/// A control client.
pub struct ControlClient(loopback::ControlClient);

impl ControlClient {
    pub async fn new(to: SocketAddr) -> ControlClient {
        ControlClient(loopback::ControlClient::new(to).await.expect("bind"))
    }

    pub async fn send(&self, c: &Control) -> Reply {
        self.0
            .request(c)
            .await
            .expect("a well-formed reply within 5 s")
    }

    /// `c`, retried every 200 ms for up to 10 s while a daemon just spawned binds its control
    /// socket: its reply, or `None` when it never answered.
    pub async fn send_when_up(&self, c: &Control) -> Option<Reply> {
        for _ in 0..50 {
            let attempt = tokio::time::timeout(Duration::from_millis(200), self.send(c));
            if let Ok(reply) = attempt.await {
                return Some(reply);
            }
        }
        None
    }

    /// A text of `/status` (the model's file, ...).
    pub async fn status_text(&self, name: &str) -> String {
        let pairs = self.0.status().await.expect("a status");
        let value = pairs.iter().find(|(k, _)| k == name);
        let text = value.and_then(|(_, v)| v.as_text());
        text.unwrap_or_else(|| panic!("no text {name}")).to_string()
    }

    pub async fn status(&self, name: &str) -> i64 {
        let pairs = self.0.status().await.expect("a status");
        loopback::counter(&pairs, name).unwrap_or_else(|| panic!("no counter {name}"))
    }
}

/// A receiver subscribed through `/subscribe` (to its own port).
#[derive(Clone)]
pub struct Receiver(loopback::Receiver);

impl Receiver {
    pub async fn subscribe(control: &ControlClient, profile: protocol::Profile) -> Receiver {
        Receiver(
            loopback::Receiver::subscribe(&control.0, profile)
                .await
                .expect("subscribed"),
        )
    }

    /// Collects compact frames in the background (so the socket buffer never fills) until
    /// `quiet` passes without one after the first.
    pub fn spawn_frames(&self, quiet: Duration) -> tokio::task::JoinHandle<Vec<(i32, Vec<f32>)>> {
        let collecting = self.0.collect(Some(quiet), Vec::new(), |got, r| {
            if let Some((h, frame)) = r.frame {
                got.push((h.frame_number, frame.positions().to_vec()));
            }
        });
        tokio::spawn(async move { collecting.finish().await.expect("receiver") })
    }

    /// [`Receiver::spawn_frames`] for component frames.
    pub fn spawn_components(&self, quiet: Duration) -> tokio::task::JoinHandle<Vec<Vec<f32>>> {
        let collecting = self.0.collect(Some(quiet), Vec::new(), |got, r| {
            if let Some(u) = r.components {
                assert_eq!(u.len(), COMPONENTS);
                got.push(u.to_vec());
            }
        });
        tokio::spawn(async move { collecting.finish().await.expect("receiver") })
    }
}
