//! The session manifest (`session.toml`) and the region map (`regions.toml`).
//!
//! ```toml
//! # session.toml
//! rate_hz = 120           # required: the takes' rate
//! [[take]]
//! file = "s03_happy.c3d"   # relative to the manifest
//! sentence = "s03"
//! emotion = "happy"
//! start = 240              # optional: first frame kept, a frame number or "2.5s"
//! end = "6.5s"             # optional: last frame kept, inclusive
//! ```
//!
//! ```toml
//! # regions.toml: region name -> marker labels or glob patterns
//! mouth = ["UpperLip*", "LowerLip*", "MouthCorner*"]
//! head_reference = ["HeadFront", "HeadTop", "HeadL", "HeadR"]
//! ```

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use globset::{Glob, GlobMatcher};
use serde::{Deserialize, Serialize};

mod near;
mod range;
mod take;
pub use range::{FrameOrTime, RangeError, TakeRange};
pub use take::SessionTake;

use near::near_labels;

/// File name of the session manifest inside a session folder.
pub const SESSION_FILE: &str = "session.toml";
/// File name of the region map inside a session folder.
pub const REGIONS_FILE: &str = "regions.toml";

/// Why a manifest or region map is unusable.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// The file could not be read or written.
    #[error("cannot access {path:?}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The file is not one to read (a device, a FIFO, too large).
    #[error(transparent)]
    Open(#[from] crate::file::OpenError),
    /// The TOML is malformed, misses a field or has an unknown one.
    #[error("invalid toml")]
    Parse(#[from] toml::de::Error),
    /// A problem inside a specific file.
    #[error("in {path:?}")]
    InFile {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        source: Box<SessionError>,
    },
    /// The manifest has no `rate_hz`.
    #[error(
        "rate_hz is required: the takes' frame rate in Hz, e.g. `rate_hz = 120` above the first \
         [[take]] (`emoshift info TAKE` shows a take's rate)"
    )]
    MissingRate,
    /// The frame rate is not positive and finite.
    #[error("rate_hz must be positive and finite, got {0}")]
    BadRate(f64),
    /// The manifest lists no take.
    #[error("session lists no [[take]]")]
    NoTakes,
    /// A take has an empty field.
    #[error("take {index} has an empty {field}")]
    EmptyField {
        /// 0-based take index.
        index: usize,
        /// Field name.
        field: &'static str,
    },
    /// Two takes name the same file.
    #[error("take file {0:?} is listed twice")]
    DuplicateFile(String),
    /// A take's `start`/`end` cannot be right whatever the take holds.
    #[error("take {file:?}")]
    BadRange {
        /// The take's file, as listed.
        file: String,
        /// What is wrong with the range.
        source: RangeError,
    },
    /// A region has an empty name or no pattern.
    #[error("region {0:?} must have a name and at least one label or pattern")]
    EmptyRegionSpec(String),
    /// A region pattern is not a valid glob.
    #[error("region {region:?}: bad pattern {pattern:?}")]
    BadPattern {
        /// Region name.
        region: String,
        /// The pattern.
        pattern: String,
        /// The glob error.
        source: globset::Error,
    },
    /// A literal (non-glob) label of a region is not among the markers.
    #[error("region {region:?} names marker {label:?}, which the take does not have{hint}")]
    UnknownLabel {
        /// Region name.
        region: String,
        /// The missing label.
        label: String,
        /// What the take has instead: labels the patterns match ignoring case, or its first
        /// markers.
        hint: String,
    },
    /// A region's patterns match none of the markers.
    #[error("region {region:?} matches no marker (patterns {patterns:?}){hint}")]
    EmptyRegion {
        /// Region name.
        region: String,
        /// Its patterns.
        patterns: Vec<String>,
        /// What the take has instead: labels the patterns match ignoring case, or its first
        /// markers.
        hint: String,
    },
    /// Serialising to TOML failed.
    #[error("cannot serialise to toml")]
    Serialize(#[from] toml::ser::Error),
}

impl SessionError {
    fn in_file(self, path: &Path) -> SessionError {
        SessionError::InFile {
            path: path.into(),
            source: Box::new(self),
        }
    }
}

fn read(path: &Path) -> Result<String, SessionError> {
    Ok(crate::file::read_to_string_bounded(
        path,
        crate::file::DEFAULT_MAX_TEXT_BYTES,
    )?)
}

/// A session manifest: the takes of a recording session and their labels.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Session {
    /// Frame rate of the takes; required (the model's rate in `train` unless `--rate` says
    /// otherwise).
    pub rate_hz: f64,
    /// The takes, in order.
    #[serde(rename = "take", default)]
    pub takes: Vec<SessionTake>,
    /// Folder take paths are relative to: the manifest's folder after [`Session::load`], empty
    /// (the current directory) after [`Session::parse`].
    #[serde(skip)]
    pub base_dir: PathBuf,
}

impl Session {
    /// Parses and validates manifest text.
    ///
    /// # Errors
    /// Malformed TOML, a missing or unknown field, or a failed [`Session::validate`].
    pub fn parse(text: &str) -> Result<Session, SessionError> {
        let session: Session = toml::from_str(text).map_err(|e| {
            match e.message().contains("missing field `rate_hz`") {
                true => SessionError::MissingRate,
                false => SessionError::Parse(e),
            }
        })?;
        session.validate()?;
        Ok(session)
    }

    /// Loads a manifest; take paths resolve relative to its folder.
    ///
    /// # Errors
    /// The file cannot be read, or [`Session::parse`] fails (the error names the file).
    pub fn load(path: &Path) -> Result<Session, SessionError> {
        let mut session = Session::parse(&read(path)?).map_err(|e| e.in_file(path))?;
        session.base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Ok(session)
    }

    /// Checks the rate, that there is a take, that no field is empty, no file repeats and no
    /// range ends before it starts (a range is checked against its take when the take is read).
    ///
    /// # Errors
    /// The first broken rule.
    pub fn validate(&self) -> Result<(), SessionError> {
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0) {
            return Err(SessionError::BadRate(self.rate_hz));
        }
        if self.takes.is_empty() {
            return Err(SessionError::NoTakes);
        }
        for (index, t) in self.takes.iter().enumerate() {
            for (field, value) in [
                ("file", &t.file),
                ("sentence", &t.sentence),
                ("emotion", &t.emotion),
            ] {
                if value.trim().is_empty() {
                    return Err(SessionError::EmptyField { index, field });
                }
            }
            if self.takes[..index].iter().any(|o| o.file == t.file) {
                return Err(SessionError::DuplicateFile(t.file.clone()));
            }
            t.range()
                .check_order()
                .map_err(|source| SessionError::BadRange {
                    file: t.file.clone(),
                    source,
                })?;
        }
        Ok(())
    }

    /// The manifest as TOML text.
    ///
    /// # Errors
    /// Serialisation failure (not expected for a valid session).
    pub fn to_toml(&self) -> Result<String, SessionError> {
        Ok(toml::to_string(self)?)
    }

    /// Path of a take's file, resolved against [`Session::base_dir`].
    pub fn path_of(&self, take: &SessionTake) -> PathBuf {
        self.base_dir.join(&take.file)
    }

    /// Paths of every take, in order.
    pub fn take_paths(&self) -> Vec<PathBuf> {
        self.takes.iter().map(|t| self.path_of(t)).collect()
    }

    /// Distinct emotion names, in order of first appearance.
    pub fn emotions(&self) -> Vec<&str> {
        let mut out: Vec<&str> = Vec::new();
        for t in &self.takes {
            if !out.contains(&t.emotion.as_str()) {
                out.push(&t.emotion);
            }
        }
        out
    }
}

/// Region map: region name -> marker labels or glob patterns (`*`, `?`, `[...]`, `{a,b}`).
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Regions {
    /// Region name -> patterns.
    pub regions: BTreeMap<String, Vec<String>>,
}

fn is_glob(pattern: &str) -> bool {
    pattern.contains(['*', '?', '[', '{'])
}

impl Regions {
    /// Parses and validates region-map text.
    ///
    /// # Errors
    /// Malformed TOML, a value that is not a list of strings, an empty region or a bad glob.
    pub fn parse(text: &str) -> Result<Regions, SessionError> {
        let regions: Regions = toml::from_str(text)?;
        regions.validate()?;
        Ok(regions)
    }

    /// Loads a region map from a file.
    ///
    /// # Errors
    /// The file cannot be read, or [`Regions::parse`] fails (the error names the file).
    pub fn load(path: &Path) -> Result<Regions, SessionError> {
        Regions::parse(&read(path)?).map_err(|e| e.in_file(path))
    }

    /// The region map as TOML text.
    ///
    /// # Errors
    /// Serialisation failure (not expected).
    pub fn to_toml(&self) -> Result<String, SessionError> {
        Ok(toml::to_string(self)?)
    }

    /// Checks that every region has a name and patterns, and that every pattern compiles.
    ///
    /// # Errors
    /// The first broken rule.
    pub fn validate(&self) -> Result<(), SessionError> {
        for (name, patterns) in &self.regions {
            if name.trim().is_empty() || patterns.is_empty() {
                return Err(SessionError::EmptyRegionSpec(name.clone()));
            }
            for p in patterns {
                matcher(name, p)?;
            }
        }
        Ok(())
    }

    /// Marker indices of each region among `labels` (ascending, no repeats).
    ///
    /// A literal label must exist (a typo must not silently shrink a region); a glob may match
    /// nothing as long as its region as a whole matches some marker.
    ///
    /// # Errors
    /// [`SessionError::BadPattern`], [`SessionError::UnknownLabel`] or
    /// [`SessionError::EmptyRegion`].
    pub fn resolve<S: AsRef<str>>(
        &self,
        labels: &[S],
    ) -> Result<BTreeMap<String, Vec<usize>>, SessionError> {
        let mut out = BTreeMap::new();
        for (name, patterns) in &self.regions {
            let mut hit = vec![false; labels.len()];
            for p in patterns {
                if is_glob(p) {
                    let m = matcher(name, p)?;
                    for (i, l) in labels.iter().enumerate() {
                        hit[i] |= m.is_match(l.as_ref());
                    }
                } else {
                    let i = labels.iter().position(|l| l.as_ref() == p).ok_or_else(|| {
                        SessionError::UnknownLabel {
                            region: name.clone(),
                            label: p.clone(),
                            hint: near_labels(labels, std::slice::from_ref(p)),
                        }
                    })?;
                    hit[i] = true;
                }
            }
            let idx: Vec<usize> = (0..labels.len()).filter(|&i| hit[i]).collect();
            if idx.is_empty() {
                return Err(SessionError::EmptyRegion {
                    region: name.clone(),
                    patterns: patterns.clone(),
                    hint: near_labels(labels, patterns),
                });
            }
            out.insert(name.clone(), idx);
        }
        Ok(out)
    }
}

fn matcher(region: &str, pattern: &str) -> Result<GlobMatcher, SessionError> {
    Glob::new(pattern)
        .map(|g| g.compile_matcher())
        .map_err(|source| SessionError::BadPattern {
            region: region.to_string(),
            pattern: pattern.to_string(),
            source,
        })
}

#[cfg(test)]
mod tests;
