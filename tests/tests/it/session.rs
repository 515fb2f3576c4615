//! Issue 33: `emoshift session` driven by a scripted performer over its OSC control. For each
//! prompt the performer replays, into the session's OSC source, the matching take of a
//! synthetic paired session (sentence k in emotion e), then stops. Along the way a take with
//! most markers missing is refused and retaken, and the process is killed mid-take and
//! resumed. Over OSC one take is deliberately played in the wrong emotion: the finish says to
//! redo it, the session offers it, `/session/redo` records it again in the same sitting, and
//! the second finish trains on it. The written session then trains and analyses to the same
//! roles and emotion space as the synthetic session's own manifest. The same through the
//! NatNet source, from the Motive stand-in.

use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use daemon::loopback;
use daemon::loopback::motive::{Motive, MotiveOptions};
use ica_core::model::IcaModel;
use protocol::natnet::{FrameOfData, MarkersetDef, ModelDefs, NatNetVersion};
use protocol::{Control, Labels, Reply, SessionControl, SessionStatus};

use super::support::*;

/// The take refused for missing markers, then retaken.
const GAPPY_TAKE: i32 = 2;
/// The take the process is killed in, then offered again after `--resume`.
const KILLED_TAKE: i32 = 5;
/// The take played in the wrong emotion (over OSC), which the finish offers to redo.
const BAD_TAKE: i32 = 9;
const EMOTIONS: [&str; 4] = ["neutral", "happy", "sad", "angry"];

/// What the scripted performer has done so far.
#[derive(Default)]
struct Plan {
    /// The next frame number.
    frame: i32,
    gappy_done: bool,
    killed: bool,
    /// Play [`BAD_TAKE`] in the wrong emotion (once); the file it stands for once played.
    bad: Option<Option<String>>,
    /// Time spent waiting for the kill and the restart.
    waited: Duration,
}

fn emoshift(args: &[&str]) {
    let out = Command::new(env!("CARGO_BIN_EXE_emoshift-e2e"))
        .args(args)
        .output()
        .expect("the binary runs");
    assert!(
        out.status.success(),
        "emoshift {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Where the scripted performer's frames go: an OSC port, or a Motive stand-in.
enum Feed {
    Osc(u16),
    NatNet(Box<Motive>),
}

impl Feed {
    /// A stand-in streaming one markerset "Face" with `labels`, multicast on loopback.
    fn natnet(labels: &[String]) -> Feed {
        let group = format!("239.255.42.99:{}", free_port())
            .parse()
            .expect("addr");
        let defs = ModelDefs {
            markersets: vec![MarkersetDef {
                name: "Face".into(),
                marker_names: labels.to_vec(),
            }],
            ..ModelDefs::default()
        };
        let motive = Motive::start(MotiveOptions {
            command: "127.0.0.1:0".parse().expect("addr"),
            multicast: Some(group),
            version: NatNetVersion::V3_0,
            defs,
            epoch: Instant::now(),
            rate_hz: 120.0,
        })
        .expect("the stand-in binds");
        Feed::NatNet(Box::new(motive))
    }

    fn args(&self) -> Vec<String> {
        match self {
            Feed::Osc(port) => vec!["--listen".into(), format!("127.0.0.1:{port}")],
            Feed::NatNet(m) => vec![
                "--natnet".into(),
                m.command_addr().to_string(),
                "--natnet-names".into(),
                "marker".into(),
            ],
        }
    }

    /// Until a just-started session is connected (NatNet: the stand-in has a new client and
    /// time passed for its model definitions).
    async fn until_connected(&self, clients_before: usize) {
        let Feed::NatNet(m) = self else { return };
        for _ in 0..100 {
            if m.clients() > clients_before {
                break;
            }
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
        tokio::time::sleep(Duration::from_millis(500)).await;
    }

    fn clients(&self) -> usize {
        match self {
            Feed::Osc(_) => 0,
            Feed::NatNet(m) => m.clients(),
        }
    }

    /// Sends `frames` frames of `take` (all when `None`), `gone` of its markers missing, frame
    /// numbers from `first`; a 1 ms pause every 8 frames keeps loopback's buffers from
    /// filling.
    async fn perform(
        &mut self,
        take: &replay::Take,
        frames: Option<usize>,
        gone: usize,
        first: i32,
    ) {
        let m = take.n_markers();
        let step_us = (1e6 / take.rate_hz) as i64;
        let mut osc = match self {
            Feed::Osc(port) => {
                let labels = Labels {
                    layout_id: 0,
                    names: take.labels.clone(),
                };
                let addr = format!("127.0.0.1:{port}").parse().expect("addr");
                Some(loopback::Source::on_loopback(&labels, addr).expect("a loopback source"))
            }
            Feed::NatNet(_) => None,
        };
        let missing: Vec<bool> = (0..m).map(|k| k < gone).collect();
        let mut natnet = FrameOfData::default();
        for f in 0..frames.unwrap_or(take.n_frames()) {
            let n = first + f as i32;
            let xyz = &take.positions[f * m * 3..(f + 1) * m * 3];
            match (&mut osc, &mut *self) {
                (Some(source), _) => source
                    .send_frame(n, i64::from(n) * step_us, xyz, &missing)
                    .expect("finite"),
                (None, Feed::NatNet(motive)) => {
                    let metres: Vec<[f32; 3]> = xyz
                        .chunks_exact(3)
                        .zip(&missing)
                        .map(|(c, &gone)| match gone {
                            true => [f32::NAN; 3],
                            false => [c[0] / 1e3, c[1] / 1e3, c[2] / 1e3],
                        })
                        .collect();
                    natnet.clear();
                    natnet.frame_number = n;
                    natnet.push_markerset("Face", &metres);
                    natnet.camera_mid_exposure = (i64::from(n) * step_us) as u64;
                    motive.send(&natnet).expect("encodes");
                }
                (None, Feed::Osc(_)) => unreachable!("an OSC feed has its source"),
            }
            if f % 8 == 7 {
                tokio::time::sleep(Duration::from_millis(1)).await;
            }
        }
        // The last datagrams reach the session before the stop does.
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

/// The session's control port, and its performer view's.
#[derive(Clone, Copy)]
struct Ports {
    control: u16,
    view: u16,
}

async fn spawn_session(dir: &Path, synth: &Path, feed: &Feed, ports: Ports, resume: bool) -> Child {
    let control = ports.control;
    let before = feed.clients();
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_emoshift-e2e"));
    cmd.arg("session")
        .arg(dir)
        .args(feed.args())
        .args(["--control", &format!("127.0.0.1:{control}")])
        .arg("--regions")
        .arg(synth.join("regions.toml"))
        .arg("--no-keyboard")
        .args(["--monitor", &format!("127.0.0.1:{}", ports.view)])
        .stdout(log(dir))
        .stderr(Stdio::inherit());
    if resume {
        cmd.arg("--resume");
    }
    let child = cmd.spawn().expect("the binary starts");
    feed.until_connected(before).await;
    child
}

/// The session's terminal, appended to `<dir>.log`.
fn log(dir: &Path) -> std::fs::File {
    std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(dir.with_extension("log"))
        .expect("a log file")
}

async fn status(control: &ControlClient) -> SessionStatus {
    let ask = Control::Session(SessionControl::Status);
    match control.send_when_up(&ask).await {
        Some(Reply::SessionStatus(s)) => s,
        other => panic!("no session status: {other:?}"),
    }
}

async fn send(control: &ControlClient, c: SessionControl) -> Reply {
    control.send(&Control::Session(c)).await
}

/// The performer view's `/session.json` (and its page holds the view's fields).
fn view(port: u16) -> serde_json::Value {
    let get = |path: &str| {
        use std::io::{Read, Write};
        let mut c = std::net::TcpStream::connect(("127.0.0.1", port)).expect("the view is up");
        write!(c, "GET {path} HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n").expect("sent");
        let mut text = String::new();
        c.read_to_string(&mut text).expect("an answer");
        text.split_once("\r\n\r\n")
            .map(|(_, b)| b.to_string())
            .expect("a body")
    };
    let page = get("/");
    assert!(
        page.contains("id=\"emotion\"") && page.contains("id=\"light\""),
        "{page}"
    );
    serde_json::from_str(&get("/session.json")).expect("json")
}

fn trained(dir: &Path) -> IcaModel {
    let path = dir.join("model.json");
    let file = std::fs::File::open(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    IcaModel::load(std::io::BufReader::new(file)).expect("a model")
}

fn sigkill(child: &mut Child) {
    let status = Command::new("kill")
        .args(["-KILL", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(status.success());
    child.wait().expect("the child is reaped");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn issue_33_a_scripted_performer_records_a_session_that_trains_like_its_source() {
    scripted_session(|_| Feed::Osc(free_port()), true).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn issue_33_the_same_session_through_natnet_from_the_motive_stand_in() {
    scripted_session(Feed::natnet, false).await;
}

/// Writes a synthetic 8 x 4 session, records it through `emoshift session` fed by `feed`
/// (given the markers' names), with one take in the wrong emotion when `bad`, and checks what
/// it trains to.
async fn scripted_session(feed: impl FnOnce(&[String]) -> Feed, bad: bool) {
    let tmp = tempfile::tempdir().expect("temp dir");
    let synth = tmp.path().join("synth");
    let s = synth.to_str().expect("utf-8");
    emoshift(&["synth", "--out", s, "--emotions", "neutral,happy,sad,angry"]);
    let labels = replay::load(&synth.join("s01_neutral.c3d"))
        .expect("a take")
        .labels;
    let mut feed = feed(&labels);
    let dir = tmp.path().join("perf");
    let cp = Ports {
        control: free_port(),
        view: free_port(),
    };
    let mut child = spawn_session(&dir, &synth, &feed, cp, false).await;
    let control =
        ControlClient::new(format!("127.0.0.1:{}", cp.control).parse().expect("addr")).await;
    let started = Instant::now();
    let mut plan = Plan {
        bad: bad.then_some(None),
        ..Plan::default()
    };
    performer(
        &mut feed,
        &control,
        (&synth, &dir),
        &mut child,
        cp,
        &mut plan,
    )
    .await;
    assert!(plan.gappy_done && plan.killed);
    let recorded = started.elapsed();
    let finish_at = Instant::now();
    assert!(matches!(
        send(&control, SessionControl::Finish).await,
        Reply::Confirm(_)
    ));
    if let Some(Some(bad_file)) = plan.bad.clone() {
        redo_offered(
            &mut feed,
            &control,
            (&synth, &dir),
            &mut child,
            cp,
            &mut plan,
            &bad_file,
        )
        .await;
    }
    let status = wait(&mut child, Duration::from_secs(300));
    assert!(status.success(), "session finished with {status}");
    let finish = finish_at.elapsed();
    eprintln!(
        "issue 33: 32 takes recorded in {:.1} s (of them {:.1} s waits for the kill and the restart), trained and analysed in {:.1} s{}",
        recorded.as_secs_f64(),
        plan.waited.as_secs_f64(),
        finish.as_secs_f64(),
        match plan.bad {
            Some(_) => " (twice, with the offered redo between)",
            None => "",
        }
    );
    let m = synth.join("session.toml");
    let (m, model) = (m.to_str().expect("utf-8"), format!("{s}/model.json"));
    emoshift(&["train", "--manifest", m, "--out", &model]);
    let report = format!("{s}/report");
    emoshift(&[
        "analyze",
        "--model",
        &model,
        "--manifest",
        m,
        "--out",
        &report,
        "--write-model",
    ]);
    same_roles_and_space(&trained(&dir), &trained(&synth));
    let said = std::fs::read_to_string(dir.with_extension("log")).expect("the session's log");
    let offered = ["to redo:", "(or /session/redo", "--resume --redo"];
    let offered = offered.iter().filter(|_| plan.bad.is_some());
    for line in [
        "REFUSED: only",
        "kept as",
        "nothing to redo",
        "roles and levels written",
    ]
    .iter()
    .chain(offered)
    {
        assert!(
            said.contains(line),
            "the session never said {line:?}:\n{said}"
        );
    }
    if let Feed::NatNet(motive) = feed {
        motive.stop();
    }
}

/// After the first finish: the bad take is offered (on the page), `/session/redo` prompts it,
/// it is played right, and a second finish trains; the old take is kept in `replaced/`.
async fn redo_offered(
    feed: &mut Feed,
    control: &ControlClient,
    (synth, dir): (&Path, &Path),
    child: &mut Child,
    cp: Ports,
    plan: &mut Plan,
    bad_file: &str,
) {
    let until = Instant::now() + Duration::from_secs(240);
    let offered = loop {
        if let Some(s) = child.try_wait().expect("waits") {
            panic!("the session ended ({s}) without offering to redo {bad_file}");
        }
        let v = view(cp.view);
        let offered: Vec<String> = v["offered"]
            .as_array()
            .map(|a| {
                a.iter()
                    .filter_map(|f| f.as_str().map(String::from))
                    .collect()
            })
            .unwrap_or_default();
        if !offered.is_empty() {
            assert!(!v["advice"].as_array().expect("advice").is_empty(), "{v}");
            break offered;
        }
        assert!(Instant::now() < until, "no redo offered: {v}");
        tokio::time::sleep(Duration::from_millis(250)).await;
    };
    assert!(
        offered.iter().any(|f| f == bad_file),
        "the take played in the wrong emotion is not offered: {offered:?}"
    );
    assert!(matches!(
        send(control, SessionControl::Redo).await,
        Reply::Confirm(_)
    ));
    let st = status(control).await;
    assert_eq!(st.state, "waiting", "{st:?}");
    performer(feed, control, (synth, dir), child, cp, plan).await;
    assert!(
        dir.join("replaced").join(bad_file).exists(),
        "the replaced take is kept"
    );
    assert!(matches!(
        send(control, SessionControl::Finish).await,
        Reply::Confirm(_)
    ));
}

/// Plays every prompted take until the session is done, refusing one with most markers
/// missing, killing the process in another, and playing [`BAD_TAKE`] in the wrong emotion
/// when the plan says so.
async fn performer(
    feed: &mut Feed,
    control: &ControlClient,
    (synth, dir): (&Path, &Path),
    child: &mut Child,
    cp: Ports,
    plan: &mut Plan,
) {
    let Plan {
        frame,
        gappy_done,
        killed,
        bad,
        waited,
    } = plan;
    loop {
        let st = status(control).await;
        if st.state == "done" {
            break;
        }
        if st.take <= 1 {
            // The performer's page shows the prompt, and the next one once a take is in.
            let v = view(cp.view);
            assert_eq!(v["take"], st.take + 1, "{v}");
            assert_eq!(
                (v["text"].as_str(), v["emotion"].as_str()),
                (Some(st.text.as_str()), Some(st.emotion.as_str()))
            );
            assert_eq!(v["state"], "waiting");
        }
        assert_eq!(st.state, "waiting", "{st:?}");
        let mut emotion = st.emotion.clone();
        if st.take == BAD_TAKE && matches!(bad, Some(None)) {
            // Two emotions on: neither this sentence's previous take nor a copy of it.
            let k = EMOTIONS.iter().position(|e| *e == emotion).expect("known");
            emotion = EMOTIONS[(k + 2) % 4].to_string();
            *bad = Some(Some(format!("s{:02}_{}.c3d", st.sentence, st.emotion)));
        }
        let file = synth.join(format!("s{:02}_{emotion}.c3d", st.sentence));
        let take = replay::load(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        assert!(matches!(
            send(control, SessionControl::Start).await,
            Reply::Confirm(_)
        ));
        if st.take == GAPPY_TAKE && !*gappy_done {
            feed.perform(&take, None, take.n_markers() * 3 / 5, *frame)
                .await;
            *frame += take.n_frames() as i32 + 10;
            let refused = send(control, SessionControl::Stop).await;
            let Reply::Error { message, .. } = &refused else {
                panic!("a take with 60 % of its markers missing was accepted: {refused:?}");
            };
            assert!(message.contains("markers"), "{message}");
            let review = status(control).await;
            assert_eq!((review.take, review.state.as_str()), (GAPPY_TAKE, "review"));
            assert!(matches!(
                send(control, SessionControl::Retake).await,
                Reply::Confirm(_)
            ));
            *gappy_done = true;
        }
        if st.take == KILLED_TAKE && !*killed {
            feed.perform(&take, Some(take.n_frames() / 2), 0, *frame)
                .await;
            *frame += take.n_frames() as i32 + 10;
            let t = Instant::now();
            // A second for the writer's sync, as a take killed at any moment would have.
            tokio::time::sleep(Duration::from_millis(1_200)).await;
            sigkill(child);
            *killed = true;
            let listed = replay::session::Session::load(&dir.join("session.toml")).expect("kept");
            assert_eq!(
                listed.takes.len(),
                KILLED_TAKE as usize,
                "every accepted take kept"
            );
            *child = spawn_session(dir, synth, feed, cp, true).await;
            let again = status(control).await;
            *waited += t.elapsed();
            assert_eq!((again.take, again.state.as_str()), (KILLED_TAKE, "waiting"));
            assert_eq!((again.sentence, &again.emotion), (st.sentence, &st.emotion));
            let kept = replay::load(&dir.join(format!(
                "interrupted/s{:02}_{}.c3d",
                st.sentence, st.emotion
            )));
            let kept = kept.expect("the interrupted take is kept and reads");
            assert!(
                kept.n_frames() >= take.n_frames() / 2 - 120,
                "{} frames",
                kept.n_frames()
            );
            continue;
        }
        feed.perform(&take, None, 0, *frame).await;
        *frame += take.n_frames() as i32 + 10;
        let stopped = send(control, SessionControl::Stop).await;
        assert!(
            matches!(stopped, Reply::Confirm(_)),
            "take {}: {stopped:?}",
            st.take
        );
    }
}

fn wait(child: &mut Child, limit: Duration) -> std::process::ExitStatus {
    let until = Instant::now() + limit;
    loop {
        if let Some(s) = child.try_wait().expect("waits") {
            return s;
        }
        if Instant::now() > until {
            let _ = child.kill();
            panic!("the session did not finish within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// The same count of each role, the same emotions, and emotion points in the same order
/// along each axis.
fn same_roles_and_space(live: &IcaModel, source: &IcaModel) {
    let count = |m: &IcaModel| {
        let mut roles: Vec<String> = m.roles().iter().map(|r| format!("{r:?}")).collect();
        roles.sort();
        roles
    };
    assert_eq!(count(live), count(source), "roles");
    for role in ["Emotion", "Speech", "Eyelids"] {
        assert!(
            count(live).iter().any(|r| r == role),
            "no {role} component: {:?}",
            count(live)
        );
    }
    let (le, se) = (live.emotion(), source.emotion());
    let mut names = le.names();
    names.sort();
    let mut want = se.names();
    want.sort();
    assert_eq!(names, want, "emotions");
    assert_eq!(want.len(), 4, "{want:?}");
    assert_eq!(le.dims(), se.dims(), "emotion space dimensions");
    let points = |e: &ica_core::model::EmotionLevels| -> Vec<Vec<f64>> {
        want.iter().map(|n| e.point(n).expect("a point")).collect()
    };
    let (lp, sp) = (points(le), points(se));
    // Distances between emotions agree (axes may differ in sign or order between fits).
    for i in 0..want.len() {
        for j in i + 1..want.len() {
            let d = |p: &[Vec<f64>]| -> f64 {
                p[i].iter()
                    .zip(&p[j])
                    .map(|(a, b)| (a - b).powi(2))
                    .sum::<f64>()
                    .sqrt()
            };
            let (dl, ds) = (d(&lp), d(&sp));
            assert!(
                (dl - ds).abs() <= 0.25 * ds.max(0.1),
                "{} to {}: {dl} vs {ds}",
                want[i],
                want[j]
            );
        }
    }
}
