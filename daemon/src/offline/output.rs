//! Where a command may write: never over one of its own inputs, and over an existing file or
//! folder only when the user said `--force`.

use std::path::{Path, PathBuf};

use anyhow::Result;

use crate::exit::UsageError;

/// The path with its folder resolved (the file itself need not exist).
fn resolved(p: &Path) -> PathBuf {
    if let Ok(c) = p.canonicalize() {
        return c;
    }
    let dir = p.parent().filter(|d| !d.as_os_str().is_empty());
    match (
        dir.map_or(std::env::current_dir(), Path::canonicalize),
        p.file_name(),
    ) {
        (Ok(d), Some(name)) => d.join(name),
        _ => p.to_path_buf(),
    }
}

/// Checks that `out` is none of `inputs`, and that it does not exist unless `force`.
///
/// # Errors
/// A [`UsageError`] naming the path and what to do.
pub fn check_out(out: &Path, inputs: &[&Path], force: bool) -> Result<()> {
    let target = resolved(out);
    if let Some(input) = inputs.iter().find(|i| resolved(i) == target) {
        return Err(UsageError(format!(
            "{} is also an input ({}); write the output elsewhere",
            out.display(),
            input.display()
        ))
        .into());
    }
    if out.is_dir() {
        // --force cannot help: the output is a file.
        return Err(UsageError(format!(
            "{} is a folder; name the output file",
            out.display()
        ))
        .into());
    }
    let exists = std::fs::symlink_metadata(out).is_ok();
    if exists && !force {
        return Err(UsageError(format!(
            "{} exists; pass --force to overwrite it",
            out.display()
        ))
        .into());
    }
    Ok(())
}

/// Checks that `out` does not name a take format the command does not write (`writes`: what
/// it writes, as a file extension): a model or a component CSV in a file named `.c3d` would
/// read back as a broken take.
///
/// # Errors
/// A [`UsageError`] naming the path and the extension to use.
pub fn check_out_format(out: &Path, writes: &str) -> Result<()> {
    let ext = out
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some(take @ ("c3d" | "trc" | "csv")) if take != writes => Err(UsageError(format!(
            "{} names a .{take} take, but this command writes .{writes}; name the output .{writes}",
            out.display()
        ))
        .into()),
        _ => Ok(()),
    }
}

/// Checks that the folder `out` is empty or absent unless `force` (its files would be
/// replaced).
///
/// # Errors
/// A [`UsageError`] naming the folder.
pub fn check_out_dir(out: &Path, force: bool) -> Result<()> {
    let busy = std::fs::read_dir(out).is_ok_and(|mut entries| entries.next().is_some());
    if busy && !force {
        return Err(UsageError(format!(
            "{} exists and is not empty; pass --force to write into it",
            out.display()
        ))
        .into());
    }
    Ok(())
}

#[cfg(test)]
mod tests;
