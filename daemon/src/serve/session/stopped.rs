//! A take stopped: closed, read back, checked, and put in place (its name, the manifest
//! written) or aside (`refused/`).

use std::path::Path;
use std::sync::Mutex;

use anyhow::{Context, Result};

use super::{files, lock, Live, SessionConfig};
use crate::offline::session::check::{self, Expect};
use crate::offline::session::Sitting;

/// Closes the take, checks it, and puts it in place (accepted: its name, the manifest
/// written) or aside (`refused/`). The inner result is the check's: the rate, or why refused.
pub(super) fn stop_and_check(
    config: &SessionConfig,
    sitting: &Sitting,
    live: &Mutex<Live>,
) -> Result<Result<f64, String>> {
    let (take, error) = {
        let mut l = lock(live);
        (l.take.take(), l.error.take())
    };
    let Some(take) = take else {
        return Ok(Err("nothing was recording".into()));
    };
    let relabelled = take.relabelled();
    let captured = take.finish()?;
    if let Some(e) = error {
        return Err(e);
    }
    let prompt = sitting.prompt().clone();
    let recording = files::recording_path(&config.dir, &prompt, sitting.ext());
    let Some(captured) = captured else {
        return Ok(Err(check::Refusal::Empty.to_string()));
    };
    let take = replay::load(&recording)
        .with_context(|| format!("cannot read back {}", recording.display()))?;
    let previous = match sitting.previous_accepted() {
        Some(p) => Some(replay::load(&config.dir.join(p.file_name(sitting.ext())))?),
        None => None,
    };
    let expect = Expect {
        seconds: sitting.script().sentences[prompt.sentence].seconds_range(),
        markers: previous.as_ref().map(|p| p.labels.as_slice()),
        min_seen: config.min_seen,
    };
    if let Err(refusal) = check::check(&take, relabelled, &expect, previous.as_ref()) {
        files::move_aside(&recording, &config.dir, "refused")?;
        return Ok(Err(refusal.to_string()));
    }
    accept(
        config,
        sitting,
        &recording,
        &prompt.file_name(sitting.ext()),
    )?;
    Ok(Ok(captured.rate_hz))
}

/// Puts an accepted take under its name (an accepted take it replaces goes to `replaced/`)
/// and writes the manifest with it.
fn accept(config: &SessionConfig, sitting: &Sitting, recording: &Path, name: &str) -> Result<()> {
    let final_path = config.dir.join(name);
    if final_path.exists() {
        files::move_aside(&final_path, &config.dir, "replaced")?;
    }
    std::fs::rename(recording, &final_path)
        .with_context(|| format!("cannot name the take {}", final_path.display()))?;
    let mut after = sitting.clone();
    after.handle_checked(Ok(0.0));
    if let Some(mut manifest) = after.manifest() {
        manifest.rate_hz = sitting.manifest().map_or(manifest.rate_hz, |m| m.rate_hz);
        files::write_manifest(&config.dir, &manifest)?;
    }
    Ok(())
}
