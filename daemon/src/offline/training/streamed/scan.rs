//! The first pass of streaming training: every take read once for what must be known before
//! any frame is prepared. The model rate, each take's frame count, how often each marker is
//! missing (which markers the model keeps) and a bounded sample of the capture
//! ([`super::sample`]). The frames, at the model rate in the first take's marker order, go to
//! a spill file, so the next pass reads them back instead of decoding every file again. A
//! session no longer than the in-memory limit is kept whole, for the in-memory path.

use anyhow::{Context, Result};
use rayon::ThreadPool;

use super::read::{at_rate, batches, for_each_batch};
use super::sample::{frames_range, Sampler};
use super::spill::{f32_bytes, Spill};
use crate::offline::progress::Progress;
use crate::offline::takes::frames_in_model_order;
use crate::offline::training::{MissingCounts, PrepOptions};
use crate::offline::{LoadedTake, ModelFrames, TakeInput};
use engine::layout::LabelMap;

/// Bytes of take files loaded at once in the first pass.
const SCAN_BATCH_BYTES: u64 = 16 << 20;

/// What the first pass found.
#[derive(Debug)]
pub(super) struct Scan {
    /// Model rate.
    pub rate_hz: f64,
    /// Markers kept, in the first take's order.
    pub labels: Vec<String>,
    /// Markers left out, with the share of frames they were missing in.
    pub excluded: Vec<(String, f64)>,
    /// One line per take whose markers differ from the first take's.
    pub label_notes: Vec<String>,
    /// Takes resampled: file, from rate, to rate.
    pub resampled: Vec<(String, f64, f64)>,
    /// Frames of each take at the model rate.
    pub take_frames: Vec<usize>,
    /// The bounded sample, in the kept markers' order.
    pub sample: Vec<ModelFrames>,
    /// Markers of the first take (the order of the spilled frames).
    pub first_markers: usize,
    /// The kept markers' indices among the first take's.
    pub kept: Vec<usize>,
    /// Every frame at the model rate in the first take's marker order: positions (f32), then
    /// one missing byte per marker (taken out by [`Scan::take_raw`]).
    pub raw: Option<Spill>,
    /// Every take as loaded, when the session is within the in-memory limit.
    pub held: Option<Vec<LoadedTake>>,
}

impl Scan {
    /// A scan of `takes` takes at `rate_hz`, the first of `first_markers` markers, holding
    /// the takes when `hold`.
    fn new(rate_hz: f64, takes: usize, first_markers: usize, hold: bool) -> Scan {
        Scan {
            rate_hz,
            labels: Vec::new(),
            excluded: Vec::new(),
            label_notes: Vec::new(),
            resampled: Vec::new(),
            take_frames: Vec::with_capacity(takes),
            sample: Vec::new(),
            first_markers,
            kept: Vec::new(),
            raw: None,
            held: hold.then(Vec::new),
        }
    }

    /// The spilled frames, taken out (the rest of the scan stays usable).
    pub(super) fn take_raw(mut self) -> Result<(Self, Spill)> {
        let raw = self.raw.take().context("the frames were spilled once")?;
        Ok((self, raw))
    }

    /// Frames in the session.
    pub(super) fn total_frames(&self) -> usize {
        self.take_frames.iter().sum()
    }

    /// The sample is the session: every take, whole, in order (a session within the
    /// sample's budget with no empty take).
    pub(super) fn sample_is_session(&self) -> bool {
        self.sample.len() == self.take_frames.len()
            && (self.sample.iter())
                .zip(&self.take_frames)
                .all(|(s, &f)| s.frames() == f)
    }
}

/// Reads every take once (see the module docs); keeps them when the session has at most
/// `hold_frames` frames.
///
/// # Errors
/// No take, an unreadable take, a take that shares no marker with the first, or every marker
/// missing too often.
pub(super) fn scan(
    takes: &[TakeInput],
    prep: &PrepOptions,
    hold_frames: usize,
    sample_frames: usize,
    pool: &ThreadPool,
    progress: &mut dyn Progress,
) -> Result<Scan> {
    progress.step("reading takes", "takes", Some(takes.len() as u64));
    let first = takes.first().context("no takes given")?;
    let first = first.load(super::DECODING)?;
    let rate_hz = prep.rate_hz.unwrap_or(first.rate_hz);
    let first_labels = first.labels.clone();
    let sizes = file_sizes(takes);
    let (hold, sample_guess) = session_guess(takes, &sizes, &first, rate_hz, hold_frames);
    let first = FirstTake(std::sync::Mutex::new(Some(first)));
    let mut counts = MissingCounts::new(first_labels.clone());
    let mut sampler = Sampler::new(sample_frames, sample_guess);
    let mut scan = Scan::new(rate_hz, takes.len(), first_labels.len(), hold);
    let mut bytes = Vec::new();
    let mut raw = Spill::new(first_labels.len() * 13)?;
    let load = |i: usize| {
        let take = first.take_or_load(i, takes)?;
        let at_rate = at_rate(&take, rate_hz);
        Ok((take, at_rate))
    };
    for_each_batch(
        pool,
        &batches(&sizes, SCAN_BATCH_BYTES),
        &load,
        &mut |range, loaded| {
            for (i, (original, at_rate)) in range.zip(loaded) {
                let path = &takes[i].path;
                if at_rate.is_some() {
                    scan.resampled
                        .push((path.display().to_string(), original.rate_hz, rate_hz));
                }
                let take = at_rate.as_ref().unwrap_or(&original);
                let all = first_take_order(path, take, &first_labels, &mut counts)?;
                sampler.push(i, all.frames(), &|r| frames_range(&all, r));
                spill_frames(&all, &mut bytes, &mut raw)?;
                scan.take_frames.push(take.n_frames());
                let total = scan.take_frames.iter().sum::<usize>();
                scan.held = hold_take(scan.held.take(), total <= hold_frames, path, original);
                progress.advance(1);
            }
            Ok(())
        },
    )?;
    let kept = counts.kept(prep.max_missing_share)?;
    let (labels, excluded) = (kept.labels, kept.excluded);
    scan.label_notes = kept.label_notes;
    let kept = positions_in(&labels, &first_labels);
    scan.raw = Some(raw);
    scan.sample = sampler.finish(&kept);
    scan.kept = kept;
    scan.labels = labels;
    scan.excluded = excluded;
    Ok(scan)
}

/// The first take, read once to learn the session's labels and rate: the first batch takes it
/// rather than reading the file again (a quarter of the reading when a session is four takes).
struct FirstTake(std::sync::Mutex<Option<replay::Take>>);

impl FirstTake {
    /// Take `i` of `takes`: the one held for the first, read for the others.
    fn take_or_load(&self, i: usize, takes: &[TakeInput]) -> Result<replay::Take> {
        let held = (i == 0).then(|| self.0.lock().ok()?.take()).flatten();
        match held {
            Some(take) => Ok(take),
            None => takes[i].load(super::DECODING),
        }
    }
}

/// Each file's size in bytes (1 when it cannot be read: the reading will say why).
fn file_sizes(takes: &[TakeInput]) -> Vec<u64> {
    takes
        .iter()
        .map(|t| std::fs::metadata(&t.path).map_or(1, |m| m.len()))
        .collect()
}

/// `take`'s frames in the first take's marker order, its missing markers counted.
fn first_take_order(
    path: &std::path::Path,
    take: &replay::Take,
    first_labels: &[String],
    counts: &mut MissingCounts,
) -> Result<ModelFrames> {
    counts
        .add(take, &path.display().to_string())
        .with_context(|| format!("{}", path.display()))?;
    let map =
        LabelMap::new(first_labels, &take.labels).with_context(|| format!("{}", path.display()))?;
    Ok(frames_in_model_order(take, &map, 0..take.n_frames()))
}

/// Whether to hold the takes (the session looks short), and the sampler's guess at the
/// session's frames.
fn session_guess(
    takes: &[TakeInput],
    sizes: &[u64],
    first: &replay::Take,
    rate_hz: f64,
    hold_frames: usize,
) -> (bool, f64) {
    // Holding takes that are dropped later only costs: hold none when the first take's
    // frames per byte (at the model rate) say the session is well past the limit. A wrong
    // guess costs time, not the model: a short session found streamed is read again.
    let likely_frames =
        first.n_frames() as f64 * (rate_hz / first.rate_hz) * sizes.iter().sum::<u64>() as f64
            / sizes.first().copied().unwrap_or(1).max(1) as f64;
    let hold = likely_frames <= 2.0 * hold_frames as f64;
    // The sampler's first stride trusts the guess only where the files are alike: a C3D first
    // take among CSV or TRC ones (several times the bytes per frame) would make the guess, and
    // the stride, several times too large, and the sample that much too small. Otherwise the
    // stride only doubles, which keeps at least half the budget.
    let first_path = &takes[0].path;
    let alike = takes
        .iter()
        .all(|t| t.path.extension() == first_path.extension());
    (hold, if alike { likely_frames } else { 0.0 })
}

/// One take's frames, model order, as raw bytes into the spill.
fn spill_frames(all: &ModelFrames, bytes: &mut Vec<u8>, raw: &mut Spill) -> Result<()> {
    bytes.clear();
    for f in 0..all.frames() {
        let (xyz, missing) = all.frame(f);
        f32_bytes(xyz, bytes);
        bytes.extend(missing.iter().map(|&m| u8::from(m)));
    }
    raw.push(bytes)
}

/// The takes held so far with this one, while the session still fits (`fits`).
fn hold_take(
    held: Option<Vec<LoadedTake>>,
    fits: bool,
    path: &std::path::Path,
    original: replay::Take,
) -> Option<Vec<LoadedTake>> {
    match held {
        Some(mut held) if fits => {
            // The in-memory path resamples by itself.
            held.push(LoadedTake {
                path: path.to_path_buf(),
                take: original,
            });
            Some(held)
        }
        _ => None,
    }
}

/// Where each of `labels` is among `first` (the first take's labels, which hold them all).
fn positions_in(labels: &[String], first: &[String]) -> Vec<usize> {
    labels
        .iter()
        .map(|l| {
            first
                .iter()
                .position(|f| f == l)
                .expect("kept labels come from the first take's")
        })
        .collect()
}
