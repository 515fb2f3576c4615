//! The input takes of a command: files given on the command line, used whole, and a
//! manifest's takes, each cut to its `start`/`end` (issue 37) wherever it is read (`train`,
//! streamed or held, `analyze`, `session`, the demo).

use std::ops::Range;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use replay::session::{Session, TakeRange};
use replay::Take;

use super::takes::{load_session, load_take_with, LoadedTake};

/// One input take of a command: its file, and the part of it used (a manifest take's
/// `start`/`end`; a file given on the command line is used whole).
#[derive(Debug, Clone, PartialEq)]
pub struct TakeInput {
    /// The file.
    pub path: PathBuf,
    /// The frames used.
    pub range: TakeRange,
}

impl From<PathBuf> for TakeInput {
    fn from(path: PathBuf) -> TakeInput {
        TakeInput {
            path,
            range: TakeRange::WHOLE,
        }
    }
}

impl TakeInput {
    /// Loads the take and keeps its range, as `decoding` says (see [`load_take_with`]).
    ///
    /// # Errors
    /// As [`load_take`](super::load_take), or a range outside the take (naming the file and what to write).
    pub fn load(&self, decoding: replay::C3dDecoding) -> Result<Take> {
        let mut take = load_take_with(&self.path, decoding)?;
        if !self.range.is_whole() {
            let range = self.frames(take.first_frame, take.rate_hz, take.n_frames())?;
            take.keep_frames(range);
        }
        Ok(take)
    }

    /// The frame indices used of a take of `frames` frames from frame number `first_frame`
    /// at `rate_hz` (all of them without a range).
    ///
    /// # Errors
    /// A range outside the take, naming the file and what to write.
    pub fn frames(&self, first_frame: i64, rate_hz: f64, frames: usize) -> Result<Range<usize>> {
        self.range
            .frames(first_frame, rate_hz, frames)
            .with_context(|| format!("{}: start/end in the session manifest", self.path.display()))
    }
}

/// The input takes of a command, without reading them: the files given, then the manifest's
/// takes with their ranges.
///
/// # Errors
/// No input, or a manifest that cannot be read.
pub fn take_inputs(manifest: Option<&Path>, files: &[PathBuf]) -> Result<Vec<TakeInput>> {
    let mut inputs: Vec<TakeInput> = files.iter().cloned().map(TakeInput::from).collect();
    if let Some(manifest) = manifest {
        inputs.extend(session_inputs(&load_session(manifest)?));
    }
    if inputs.is_empty() {
        bail!("no takes given: pass --manifest session.toml or take files");
    }
    Ok(inputs)
}

/// A session's takes, with their ranges.
pub fn session_inputs(session: &Session) -> impl Iterator<Item = TakeInput> + '_ {
    session.takes.iter().map(|t| TakeInput {
        path: session.path_of(t),
        range: t.range(),
    })
}

/// The input takes of a command: the manifest's takes (each cut to its range), or the files
/// given.
///
/// # Errors
/// No input, or any take that cannot be loaded.
pub fn load_inputs(manifest: Option<&Path>, files: &[PathBuf]) -> Result<Vec<LoadedTake>> {
    take_inputs(manifest, files)?
        .into_iter()
        .map(|input| {
            let take = input.load(replay::C3dDecoding::CrossChecked)?;
            Ok(LoadedTake {
                path: input.path,
                take,
            })
        })
        .collect()
}
