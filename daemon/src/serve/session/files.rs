//! The session folder's files: a take is recorded as `<name>.recording.<ext>` and becomes
//! `<name>.<ext>` once accepted; refused, interrupted and replaced takes are moved into
//! `refused/`, `interrupted/` and `replaced/` under a free name, never deleted or overwritten.
//! `session.toml` is written to a temporary file, synced, then renamed over the old one.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use replay::session::Session;

use crate::offline::session::script::Prompt;

/// The manifest's name in the session folder.
pub const MANIFEST: &str = "session.toml";
/// The script's copy in the session folder (what `--resume` follows).
pub const SCRIPT: &str = "script.toml";

/// Where a take is written while it records.
pub fn recording_path(dir: &Path, prompt: &Prompt, ext: &str) -> PathBuf {
    let name = prompt.file_name(ext);
    let stem = name.trim_end_matches(&format!(".{ext}"));
    dir.join(format!("{stem}.recording.{ext}"))
}

/// Moves `path` into `dir/<folder>/` under its name, or `<stem>-<k>.<ext>` when taken.
/// Returns where it went.
///
/// # Errors
/// The folder cannot be made or the file moved.
pub fn move_aside(path: &Path, dir: &Path, folder: &str) -> Result<PathBuf> {
    let into = dir.join(folder);
    fs::create_dir_all(&into).with_context(|| format!("cannot create {}", into.display()))?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().replace(".recording", ""))
        .unwrap_or_default();
    let (stem, ext) = name.rsplit_once('.').unwrap_or((&name, ""));
    let mut to = into.join(&name);
    let mut k = 2;
    while to.exists() {
        to = into.join(format!("{stem}-{k}.{ext}"));
        k += 1;
    }
    fs::rename(path, &to)
        .with_context(|| format!("cannot move {} to {}", path.display(), to.display()))?;
    Ok(to)
}

/// Leftover `*.recording.*` files of a session that stopped mid-take, moved to
/// `interrupted/`. Returns where they went.
///
/// # Errors
/// The folder cannot be read or a file moved.
pub fn set_aside_interrupted(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut moved = Vec::new();
    for entry in fs::read_dir(dir).with_context(|| format!("cannot read {}", dir.display()))? {
        let path = entry?.path();
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
        if name.is_some_and(|n| n.contains(".recording.")) && path.is_file() {
            moved.push(move_aside(&path, dir, "interrupted")?);
        }
    }
    Ok(moved)
}

/// Writes `text` to `path` so that a crash leaves the old file or the new one, whole.
///
/// # Errors
/// The file cannot be written, synced or renamed.
pub fn write_atomically(path: &Path, text: &str) -> Result<()> {
    let temp = path.with_extension("toml.partial");
    let mut f =
        fs::File::create(&temp).with_context(|| format!("cannot create {}", temp.display()))?;
    f.write_all(text.as_bytes())
        .and_then(|()| f.sync_all())
        .with_context(|| format!("cannot write {}", temp.display()))?;
    fs::rename(&temp, path).with_context(|| format!("cannot replace {}", path.display()))?;
    if let Some(parent) = path.parent().and_then(|p| fs::File::open(p).ok()) {
        // The rename itself survives a power cut once the folder is synced.
        let _ = parent.sync_all();
    }
    Ok(())
}

/// Writes the manifest of the accepted takes.
///
/// # Errors
/// As [`write_atomically`].
pub fn write_manifest(dir: &Path, manifest: &Session) -> Result<()> {
    let text = manifest.to_toml().context("cannot write session.toml")?;
    write_atomically(&dir.join(MANIFEST), &text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nothing_moved_aside_is_overwritten() {
        let dir = tempfile::tempdir().expect("temp dir");
        let prompt = Prompt {
            sentence: 0,
            emotion: "sad".into(),
        };
        let path = recording_path(dir.path(), &prompt, "c3d");
        assert!(path.ends_with("s01_sad.recording.c3d"));
        let mut went = Vec::new();
        for k in 0..2 {
            fs::write(&path, format!("take {k}")).expect("write");
            went.extend(set_aside_interrupted(dir.path()).expect("moved"));
        }
        assert_eq!(went[0], dir.path().join("interrupted/s01_sad.c3d"));
        assert_eq!(went[1], dir.path().join("interrupted/s01_sad-2.c3d"));
        assert_eq!(fs::read_to_string(&went[0]).expect("kept"), "take 0");
        write_atomically(&dir.path().join(MANIFEST), "a").expect("written");
        write_atomically(&dir.path().join(MANIFEST), "b").expect("replaced");
        assert_eq!(
            fs::read_to_string(dir.path().join(MANIFEST)).expect("read"),
            "b"
        );
    }
}
