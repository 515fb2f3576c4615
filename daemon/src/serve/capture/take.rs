//! One take being captured from a live stream ([`Take`]): the stream chosen (by name, or the
//! first seen), frames written as they come with their timecode, lost frame numbers as gaps,
//! the rate announced by the source or else measured, and the measured rate kept beside it.
//!
//! The file opens once the rate is known: at once when the source announced it (NatNet's
//! `FrameRate`), otherwise after a second of frames held in memory to measure it (bounded:
//! [`MEASURE_FRAMES`]), or at the end for a shorter take.

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use protocol::{FrameBuf, FrameHeader, Smpte};
use replay::recorder::{RecordSummary, RecordTime, Recorder};

/// Frames held to measure the rate of a source that does not announce it.
pub const MEASURE_FRAMES: usize = 240;
/// ... or this much capture time, whichever comes first.
const MEASURE_SECONDS: f64 = 1.0;
/// Lost frame numbers written as gaps at most; a longer jump is a restart, not a gap.
const MAX_GAP: i64 = 7_200;

/// One labelled frame as a source delivered it.
#[derive(Debug, Clone, Copy)]
pub struct Incoming<'a> {
    /// The stream's name (a NatNet markerset, or `ip:port/layout`).
    pub stream: &'a str,
    /// Its labels, frame order.
    pub labels: &'a [String],
    /// The frame (mm, missing markers flagged).
    pub frame: &'a FrameBuf,
    /// Its header.
    pub header: FrameHeader,
    /// Its timecode, if any.
    pub timecode: Option<Smpte>,
    /// The rate the source announced, if it did.
    pub announced_rate_hz: Option<f64>,
    /// When it was received.
    pub received: Instant,
}

#[derive(Debug)]
struct Held {
    number: i32,
    xyz: Vec<f32>,
    missing: Vec<bool>,
    timecode: Option<Smpte>,
}

/// The take being written.
#[derive(Debug)]
pub struct Take {
    path: PathBuf,
    wanted: Option<String>,
    stream: Option<(String, Vec<String>)>,
    others: Vec<String>,
    recorder: Option<Recorder>,
    held: VecDeque<Held>,
    first: Option<(i32, i64, Instant)>,
    last: Option<(i32, i64, Instant)>,
    announced: Option<f64>,
    first_timecode: Option<Smpte>,
    frames: u64,
    gaps: u64,
    relabelled: u64,
    xyz: Vec<f32>,
    missing: Vec<bool>,
}

/// What a finished take holds.
#[derive(Debug, Clone, PartialEq)]
pub struct Captured {
    /// The file.
    pub summary: RecordSummary,
    /// The stream recorded.
    pub stream: String,
    /// The rate written (announced, else measured).
    pub rate_hz: f64,
    /// The rate announced by the source.
    pub announced_hz: Option<f64>,
    /// The rate measured from capture times.
    pub measured_hz: Option<f64>,
    /// Frames written as gaps because their numbers never arrived.
    pub gap_frames: u64,
    /// The first frame's timecode.
    pub first_timecode: Option<Smpte>,
    /// Streams seen but not recorded.
    pub others: Vec<String>,
}

impl Take {
    /// A take to `path`, of the stream named `wanted` (the first stream seen when `None`).
    pub fn new(path: &Path, wanted: Option<String>) -> Take {
        Take {
            path: path.to_path_buf(),
            wanted,
            stream: None,
            others: Vec::new(),
            recorder: None,
            held: VecDeque::new(),
            first: None,
            last: None,
            announced: None,
            first_timecode: None,
            frames: 0,
            gaps: 0,
            relabelled: 0,
            xyz: Vec::new(),
            missing: Vec::new(),
        }
    }

    /// Frames taken so far (written or held), gaps included.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Frames written as gaps so far.
    pub fn gaps(&self) -> u64 {
        self.gaps
    }

    /// Frames of the stream that came with other labels than its first frame's (a label
    /// change mid-take), left out.
    pub fn relabelled(&self) -> u64 {
        self.relabelled
    }

    /// The stream being recorded, once one was chosen.
    pub fn stream(&self) -> Option<&str> {
        self.stream.as_ref().map(|s| s.0.as_str())
    }

    /// The stream asked for and the streams seen instead, while the one asked for has not come
    /// (a `--performer` that names no stream of the source); `None` otherwise.
    pub fn wanted_missing(&self) -> Option<(&str, &[String])> {
        match (&self.wanted, &self.stream) {
            (Some(w), None) if !self.others.is_empty() => Some((w, &self.others)),
            _ => None,
        }
    }

    /// Seconds of capture since the first frame (capture times, else arrival).
    pub fn seconds(&self) -> f64 {
        match (self.first, self.last) {
            (Some(a), Some(b)) if b.1 > a.1 => (b.1 - a.1) as f64 / 1e6,
            (Some(a), Some(b)) => b.2.saturating_duration_since(a.2).as_secs_f64(),
            _ => 0.0,
        }
    }

    /// Takes one frame; frames of other streams are counted and skipped.
    ///
    /// # Errors
    /// The file cannot be created or written.
    pub fn push(&mut self, f: &Incoming<'_>) -> Result<()> {
        if !self.is_ours(f) {
            return Ok(());
        }
        let capture = f.header.capture_time_us;
        if let Some((last, _, _)) = self.last {
            let step = i64::from(f.header.frame_number) - i64::from(last);
            if step <= 0 {
                return Ok(()); // a duplicate or late frame
            }
            if step > 1 && step <= MAX_GAP {
                for k in 1..step {
                    self.hold_or_write(last.wrapping_add(k as i32), None, None)?;
                    self.gaps += 1;
                }
            }
        }
        self.announced = self.announced.or(f.announced_rate_hz);
        self.first
            .get_or_insert((f.header.frame_number, capture, f.received));
        self.first_timecode = self.first_timecode.or(f.timecode);
        self.last = Some((f.header.frame_number, capture, f.received));
        let n = f.labels.len();
        self.xyz.clear();
        self.xyz.extend_from_slice(&f.frame.positions()[..n * 3]);
        self.missing.clear();
        self.missing.extend((0..n).map(|i| f.frame.is_missing(i)));
        let (xyz, missing) = (
            std::mem::take(&mut self.xyz),
            std::mem::take(&mut self.missing),
        );
        let r = self.hold_or_write(f.header.frame_number, Some((&xyz, &missing)), f.timecode);
        (self.xyz, self.missing) = (xyz, missing);
        r
    }

    fn is_ours(&mut self, f: &Incoming<'_>) -> bool {
        match &self.stream {
            Some((name, labels)) => {
                if name != f.stream || labels.as_slice() != f.labels {
                    self.relabelled += u64::from(name == f.stream);
                    if !self.others.iter().any(|o| o == f.stream) && name != f.stream {
                        self.others.push(f.stream.to_string());
                    }
                    return false;
                }
                true
            }
            None if self.wanted.as_deref().is_none_or(|w| w == f.stream) => {
                self.stream = Some((f.stream.to_string(), f.labels.to_vec()));
                true
            }
            None => {
                if !self.others.iter().any(|o| o == f.stream) {
                    self.others.push(f.stream.to_string());
                }
                false
            }
        }
    }

    /// Writes a frame (`None` samples: a gap), holding it while the rate is unknown.
    fn hold_or_write(
        &mut self,
        number: i32,
        samples: Option<(&[f32], &[bool])>,
        timecode: Option<Smpte>,
    ) -> Result<()> {
        self.frames += 1;
        let n = self.stream.as_ref().map_or(0, |s| s.1.len());
        let (xyz, missing) = match samples {
            Some((x, m)) => (x.to_vec(), m.to_vec()),
            None => (vec![0.0; n * 3], vec![true; n]),
        };
        self.held.push_back(Held {
            number,
            xyz,
            missing,
            timecode,
        });
        let ready = self.recorder.is_some()
            || self.announced.is_some()
            || self.held.len() >= MEASURE_FRAMES
            || self.seconds() >= MEASURE_SECONDS;
        if ready {
            self.write_held()?;
        }
        Ok(())
    }

    /// Opens the file if needed and writes every held frame.
    fn write_held(&mut self) -> Result<()> {
        if self.recorder.is_none() {
            let Some(first) = self.held.front().map(|h| h.number) else {
                return Ok(());
            };
            let labels = self
                .stream
                .as_ref()
                .map(|s| s.1.clone())
                .unwrap_or_default();
            let time = RecordTime {
                timecode: self.first_timecode,
                camera_rate_hz: self.measured(),
            };
            let rate = self.rate();
            let rec = Recorder::create_timed(&self.path, labels, rate, i64::from(first), time)
                .with_context(|| format!("creating {}", self.path.display()))?;
            self.recorder = Some(rec);
        }
        let rec = self.recorder.as_mut().expect("opened above");
        while let Some(h) = self.held.pop_front() {
            rec.push_frame_timed(&h.xyz, &h.missing, h.timecode.as_ref())
                .with_context(|| format!("writing {}", self.path.display()))?;
        }
        Ok(())
    }

    /// Frames per second from the capture times (else arrival), over the whole take so far.
    pub fn measured(&self) -> Option<f64> {
        let ((f0, _, _), (f1, _, _)) = (self.first?, self.last?);
        let frames = f64::from(f1) - f64::from(f0);
        let secs = self.seconds();
        (frames >= 1.0 && secs > 0.0).then(|| frames / secs)
    }

    /// The rate the file is written at: announced, else measured (a whole number when within
    /// 0.2 % of one), else 120.
    pub fn rate(&self) -> f64 {
        if let Some(a) = self.announced {
            return a;
        }
        match self.measured() {
            Some(m) if (m - m.round()).abs() <= m * 0.002 => m.round(),
            Some(m) => (m * 1e3).round() / 1e3,
            None => 120.0,
        }
    }

    /// Writes what is held and closes the file. `None` when no frame of the stream came.
    ///
    /// # Errors
    /// The file cannot be created, written or finished.
    pub fn finish(mut self) -> Result<Option<Captured>> {
        if self.stream.is_none() {
            return Ok(None);
        }
        self.write_held()?;
        let measured = self.measured();
        let rate = self.rate();
        let Some(mut rec) = self.recorder.take() else {
            return Ok(None);
        };
        if let Some(m) = measured {
            rec.set_camera_rate(m);
        }
        let summary = rec
            .finish()
            .with_context(|| format!("finishing {}", self.path.display()))?;
        Ok(Some(Captured {
            summary,
            stream: self.stream.map(|s| s.0).unwrap_or_default(),
            rate_hz: rate,
            announced_hz: self.announced,
            measured_hz: measured,
            gap_frames: self.gaps,
            first_timecode: self.first_timecode,
            others: self.others,
        }))
    }
}
