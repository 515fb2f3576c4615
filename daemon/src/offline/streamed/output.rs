//! An output file written under a hidden name beside its destination and renamed over it only
//! when complete, so a command that fails half way through a long take leaves no partial file
//! (and an existing output, overwritten with `--force`, stays intact until then).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

/// An output being written; dropped without [`PendingOut::commit`], its file is removed.
#[derive(Debug)]
pub(crate) struct PendingOut {
    partial: PathBuf,
    out: PathBuf,
    committed: bool,
}

impl PendingOut {
    /// The hidden sibling of `out`: `.<name>.partial-<pid>.<ext>`, same extension so the
    /// format follows it.
    pub(crate) fn new(out: &Path) -> PendingOut {
        let name = out
            .file_stem()
            .map_or_else(Default::default, |s| s.to_string_lossy());
        let ext = out
            .extension()
            .map_or_else(Default::default, |s| s.to_string_lossy());
        let hidden = format!(".{name}.partial-{}.{ext}", std::process::id());
        PendingOut {
            partial: out.with_file_name(hidden),
            out: out.to_path_buf(),
            committed: false,
        }
    }

    /// Where to write.
    pub(crate) fn path(&self) -> &Path {
        &self.partial
    }

    /// Moves the complete file to its destination.
    ///
    /// # Errors
    /// The rename fails, naming the output.
    pub(crate) fn commit(mut self) -> Result<()> {
        std::fs::rename(&self.partial, &self.out)
            .with_context(|| format!("cannot write {}", self.out.display()))?;
        self.committed = true;
        Ok(())
    }
}

impl Drop for PendingOut {
    fn drop(&mut self) {
        if !self.committed {
            // Best effort: the file may never have been created.
            let _ = std::fs::remove_file(&self.partial);
        }
    }
}
