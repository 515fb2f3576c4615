//! The command line on inputs a user did not mean: devices and huge files, outputs over
//! inputs or over existing files, broken manifests and configs; and logs fit for a file.

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::common::{ok, p, run};

fn stderr_of(args: &[&str]) -> (Option<i32>, String) {
    let out = run(args);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn a_take_that_links_to_a_device_is_refused_by_name() {
    let dir = tempfile::tempdir().expect("temp dir");
    let link = dir.path().join("zero.trc");
    std::os::unix::fs::symlink("/dev/zero", &link).expect("symlink");
    let t = Instant::now();
    let (code, err) = stderr_of(&["info", p(&link)]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("not a regular file"), "{err}");
    assert!(
        !err.contains("panicked") && !err.contains("memory allocation"),
        "{err}"
    );
    assert!(t.elapsed() < Duration::from_secs(5));
    let big = dir.path().join("big.trc");
    std::fs::write(&big, vec![b'x'; 3 << 20]).expect("writable");
    let (code, err) = stderr_of(&["--max-input-mb", "2", "info", p(&big)]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("over the limit"), "{err}");
}

#[test]
fn an_output_never_replaces_an_input_and_replaces_a_file_only_with_force() {
    let dir = tempfile::tempdir().expect("temp dir");
    let session = dir.path().join("s");
    ok(&[
        "synth",
        "--out",
        p(&session),
        "--sentences",
        "1",
        "--format",
        "trc",
    ]);
    let take = session.join("s01_happy.trc");
    let before = std::fs::read(&take).expect("take");
    let (code, err) = stderr_of(&["convert", p(&take), p(&take)]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("also an input"), "{err}");
    assert_eq!(std::fs::read(&take).expect("take"), before, "untouched");
    let out = dir.path().join("out.csv");
    ok(&["convert", p(&take), p(&out)]);
    let (code, err) = stderr_of(&["convert", p(&take), p(&out)]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("--force"), "{err}");
    ok(&["convert", p(&take), p(&out), "--force"]);
    let (code, err) = stderr_of(&["synth", "--out", p(&session), "--sentences", "1"]);
    assert_eq!(code, Some(2), "a session folder in use: {err}");
}

#[test]
fn a_broken_manifest_is_explained_once() {
    let dir = tempfile::tempdir().expect("temp dir");
    let manifest = dir.path().join("session.toml");
    std::fs::write(&manifest, "[[take]]\nfile = 3\n").expect("writable");
    let out = dir.path().join("m.json");
    let (code, err) = stderr_of(&["train", "--manifest", p(&manifest), "--out", p(&out)]);
    assert_eq!(code, Some(1), "{err}");
    assert_eq!(err.matches("invalid type").count(), 1, "{err}");
    assert_eq!(err.matches("session.toml").count(), 1, "{err}");
}

#[test]
fn a_config_value_of_the_wrong_type_names_its_key_and_line() {
    let dir = tempfile::tempdir().expect("temp dir");
    let config = dir.path().join("emoshift.toml");
    std::fs::write(&config, "model = \"m.json\"\nqueue = \"big\"\n").expect("writable");
    let (code, err) = stderr_of(&["serve", "--config", p(&config)]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("line 2") && err.contains("key queue"), "{err}");
}

#[test]
fn logs_piped_to_a_file_have_no_colour_and_answer_to_the_emoshift_target() {
    let dir = tempfile::tempdir().expect("temp dir");
    let session = dir.path().join("s");
    ok(&["synth", "--out", p(&session), "--sentences", "1"]);
    let model = dir.path().join("m.json");
    ok(&[
        "train",
        "--manifest",
        p(&session.join("session.toml")),
        "--out",
        p(&model),
        "--components",
        "4",
    ]);
    let child = Command::new(env!("CARGO_BIN_EXE_emoshift"))
        .args(["serve", "--model", p(&model)])
        .args(["--listen", "127.0.0.1:0", "--control", "127.0.0.1:0"])
        .env("RUST_LOG", "warn,emoshift=info")
        .env_remove("NO_COLOR")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary starts");
    std::thread::sleep(Duration::from_millis(700));
    let killed = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(killed.success());
    let out = child.wait_with_output().expect("exits");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("serving"),
        "the emoshift target is selected: {err}"
    );
    assert!(!err.contains('\u{1b}'), "no ANSI codes in a pipe: {err:?}");
}
