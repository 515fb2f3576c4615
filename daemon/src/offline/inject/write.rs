//! An injected session on disk: one take file per cut, `session.toml`, and the truth
//! (`truth/inject.json`: the field, the head reference, every cut and its level).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use replay::session::{Session, SessionTake, SESSION_FILE};
use serde::Serialize;

use super::{Cut, InjectedSession};

/// The truth file, under the session folder.
pub const TRUTH_FILE: &str = "truth/inject.json";

/// What `truth/inject.json` holds.
#[derive(Debug, Clone, Serialize)]
pub struct InjectTruth {
    /// Seed of the field, the cuts and the paces.
    pub seed: u64,
    /// Level names, lowest first; level `i` of `n` adds `i / (n − 1)` times the field.
    pub levels: Vec<String>,
    /// RMS of the field over the face markers at the top level, mm.
    pub field_mm: f64,
    /// Markers whose frame the field is in (empty: world coordinates).
    pub head_reference: Vec<String>,
    /// The field at the top level in head coordinates: label and x, y, z (mm).
    pub field: Vec<(String, [f64; 3])>,
    /// The captures cut, in order (`Cut::capture` indexes them).
    pub captures: Vec<String>,
    /// Every take.
    pub cuts: Vec<Cut>,
}

impl InjectedSession {
    /// The truth of the session.
    pub fn truth(&self) -> InjectTruth {
        let labels = &self.captures[0].take.labels;
        InjectTruth {
            seed: self.params.seed,
            levels: self.level_names(),
            field_mm: self.params.field_mm,
            head_reference: self.head.clone(),
            field: labels
                .iter()
                .enumerate()
                .map(|(m, l)| {
                    let v = &self.field[m * 3..m * 3 + 3];
                    (l.clone(), [v[0], v[1], v[2]])
                })
                .collect(),
            captures: self.captures.iter().map(|c| c.name.clone()).collect(),
            cuts: self.cuts.clone(),
        }
    }

    /// The manifest, with take files named `<cut>.<format extension>`.
    pub fn manifest(&self, format: replay::Format) -> Session {
        Session {
            rate_hz: self.captures[0].take.rate_hz,
            takes: self
                .cuts
                .iter()
                .map(|c| {
                    SessionTake::whole(
                        format!("{}.{}", c.name, format.extension()),
                        c.sentence.clone(),
                        c.emotion.clone(),
                    )
                })
                .collect(),
            base_dir: PathBuf::new(),
        }
    }
}

/// Writes every take of `session` in `format`, `session.toml` and the truth into `dir`
/// (created if needed); returns the manifest's path.
///
/// # Errors
/// Any file that cannot be written.
pub fn write_session(
    dir: &Path,
    session: &InjectedSession,
    format: replay::Format,
) -> Result<PathBuf> {
    std::fs::create_dir_all(dir.join("truth"))
        .with_context(|| format!("cannot create {}", dir.display()))?;
    let manifest = session.manifest(format);
    for (cut, entry) in session.cuts().iter().zip(&manifest.takes) {
        let path = dir.join(&entry.file);
        replay::save(&path, &session.render(cut, cut.level))
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    let write = |path: PathBuf, text: String| {
        std::fs::write(&path, text).with_context(|| format!("cannot write {}", path.display()))
    };
    let json = serde_json::to_string_pretty(&session.truth()).context("truth serialisation")?;
    write(dir.join(TRUTH_FILE), json)?;
    let path = dir.join(SESSION_FILE);
    write(path.clone(), manifest.to_toml()?)?;
    Ok(path)
}
