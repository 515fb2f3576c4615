//! Reading takes for streaming training: in batches loaded (or read back from the first
//! pass's spill) and prepared on the pool, handed to the caller one batch at a time, in take
//! order, so the passes stay deterministic whatever the thread count and memory holds one
//! batch.

use anyhow::Result;
use ica_core::model::CaptureSettings;
use rayon::prelude::*;
use rayon::ThreadPool;
use replay::Take;
use std::ops::Range;

use super::sample::narrow;
use super::spill::f32_values;
use crate::offline::training::capture::HeadFrames;
use crate::offline::ModelFrames;
use engine::frame::FramePrep;

/// Consecutive items whose sizes add up to about `target` (at least one item each). The first
/// batches are smaller (a quarter, then half the target): the pipelines below work on one
/// batch while the next loads, and nothing overlaps the first one's loading.
pub(super) fn batches(sizes: &[u64], target: u64) -> Vec<Range<usize>> {
    let mut out = Vec::new();
    let (mut start, mut sum) = (0, 0u64);
    for (i, &size) in sizes.iter().enumerate() {
        sum += size;
        let ramp = match out.len() {
            0 => 4,
            1 => 2,
            _ => 1,
        };
        if sum >= target / ramp {
            out.push(start..i + 1);
            start = i + 1;
            sum = 0;
        }
    }
    if start < sizes.len() {
        out.push(start..sizes.len());
    }
    out
}

/// Loads every item of each batch on the pool with `load`, then calls `each` with the batch's
/// results in order; stops at the first error. The next batch loads while `each` works on
/// the current one, so memory holds two batches and the pool does not wait for `each`.
///
/// # Errors
/// The first error of `load` or `each`.
pub(super) fn for_each_batch<T: Send>(
    pool: &ThreadPool,
    batches: &[Range<usize>],
    load: &(dyn Fn(usize) -> Result<T> + Sync),
    each: &mut dyn FnMut(Range<usize>, Vec<T>) -> Result<()>,
) -> Result<()> {
    let load_batch = |range: &Range<usize>| {
        pool.install(|| {
            range
                .clone()
                .into_par_iter()
                .map(load)
                .collect::<Result<Vec<T>>>()
        })
    };
    let Some(first) = batches.first() else {
        return Ok(());
    };
    let mut loaded = load_batch(first)?;
    for (k, range) in batches.iter().enumerate() {
        let current = std::mem::take(&mut loaded);
        let (next, done) = std::thread::scope(|s| {
            let next = batches.get(k + 1).map(|r| s.spawn(|| load_batch(r)));
            let done = each(range.clone(), current);
            (next.map(std::thread::ScopedJoinHandle::join), done)
        });
        done?;
        if let Some(next) = next {
            loaded = next.map_err(|_| anyhow::anyhow!("a take loader panicked"))??;
        }
    }
    Ok(())
}

/// The take resampled to the model rate, when its rate differs (as the in-memory path
/// decides).
pub(super) fn at_rate(take: &Take, rate_hz: f64) -> Option<Take> {
    ((take.rate_hz - rate_hz).abs() > 1e-6 * rate_hz).then(|| take.resampled(rate_hz))
}

/// One take through the frame preparation training uses (glitches, head coordinates).
#[derive(Debug)]
pub(super) struct PreparedTake {
    /// Frames.
    pub frames: usize,
    /// Prepared positions, frames x markers x 3.
    pub xyz: Vec<f32>,
    /// Missing after preparation (glitches included), frames x markers.
    pub missing: Vec<bool>,
    /// Missing in the file, frames x markers (model order).
    pub raw_missing: Vec<bool>,
    /// Samples dropped as glitches.
    pub glitches: usize,
    /// Stabilisation residual of each frame whose pose was estimated (mm).
    pub residuals: Vec<f64>,
}

/// What preparing a take needs: the model's markers, rate and capture settings.
#[derive(Debug, Clone)]
pub(super) struct TakePrep<'a> {
    /// The kept markers' indices among the spilled frames' markers.
    pub kept: &'a [usize],
    /// Markers of a spilled frame.
    pub spilled_markers: usize,
    pub rate_hz: f64,
    pub capture: &'a CaptureSettings,
    /// The session already in head coordinates, when the sample holds it whole.
    pub stabilised: Option<Stabilised<'a>>,
}

/// A session the head sample holds whole, as the glitch limits' pass prepared it
/// ([`HeadFrames`]: head coordinates, no glitch check): preparing it again only runs the
/// glitch checks, with the same result as stabilising every frame again (the pose is fitted
/// before the checks, on the frame's mask as read).
#[derive(Debug, Clone)]
pub(super) struct Stabilised<'a> {
    /// Every take's frames end to end.
    pub frames: &'a HeadFrames,
    /// Each take's frames as read (the sample): their masks before preparation.
    pub takes: &'a [ModelFrames],
    /// Where each take starts in `frames` (in frames).
    pub starts: Vec<usize>,
}

impl TakePrep<'_> {
    /// Prepares every frame of take number `take`, spilled by the first pass
    /// ([`super::scan`]) as `bytes`, or already stabilised ([`Stabilised`]).
    ///
    /// # Errors
    /// A frame buffer that does not match the markers (an internal invariant).
    pub(super) fn prepare(&self, take: usize, bytes: &[u8]) -> Result<PreparedTake> {
        if let Some(s) = &self.stabilised {
            return self.check_glitches(s, take);
        }
        let raw = narrow(self.unspill(bytes), self.kept);
        let mut prep = FramePrep::new(self.kept.len(), self.rate_hz, self.capture);
        let frames = (0..raw.frames()).map(|f| raw.frame(f));
        let mut out = prepare_frames(&mut prep, raw.frames(), frames)?;
        out.raw_missing = raw.missing;
        Ok(out)
    }

    /// Take number `take` of a stabilised session with the glitch checks run on it.
    fn check_glitches(&self, s: &Stabilised<'_>, take: usize) -> Result<PreparedTake> {
        let n = self.kept.len();
        let (raw, start) = (&s.takes[take], s.starts[take]);
        let range = start..start + raw.frames();
        let xyz = &s.frames.xyz[range.start * n * 3..range.end * n * 3];
        let missing = &s.frames.missing[range.start * n..range.end * n];
        let checks = CaptureSettings {
            head: None,
            ..self.capture.clone()
        };
        let mut prep = FramePrep::new(n, self.rate_hz, &checks);
        let frames = xyz.chunks_exact(n * 3).zip(missing.chunks_exact(n));
        let mut out = prepare_frames(&mut prep, raw.frames(), frames)?;
        out.raw_missing.clone_from(&raw.missing);
        Ok(out)
    }

    /// The spilled frames back as positions and mask.
    fn unspill(&self, bytes: &[u8]) -> ModelFrames {
        let n = self.spilled_markers;
        let (mut xyz, mut missing, mut frame) = (Vec::new(), Vec::new(), Vec::new());
        for record in bytes.chunks_exact(13 * n) {
            f32_values(&record[..12 * n], &mut frame);
            xyz.extend_from_slice(&frame);
            missing.extend(record[12 * n..].iter().map(|&b| b != 0));
        }
        ModelFrames {
            xyz,
            missing,
            markers: n,
        }
    }
}

/// `count` frames (positions and mask) through `prep`; the take's `raw_missing` left empty.
fn prepare_frames<'f>(
    prep: &mut FramePrep,
    count: usize,
    frames: impl Iterator<Item = (&'f [f32], &'f [bool])>,
) -> Result<PreparedTake> {
    let n = prep.markers();
    let mut out = PreparedTake {
        frames: count,
        xyz: Vec::with_capacity(count * n * 3),
        missing: Vec::with_capacity(count * n),
        raw_missing: Vec::new(),
        glitches: 0,
        residuals: Vec::new(),
    };
    for (p, m) in frames {
        let done = prep.prepare(p, m)?;
        out.xyz.extend_from_slice(done.xyz);
        out.missing.extend_from_slice(done.missing);
        out.glitches += done.info.glitches;
        if done.info.pose.is_some() && !done.info.pose_held {
            out.residuals.push(done.info.residual_mm);
        }
    }
    Ok(out)
}

/// A batch of prepared takes as the fit reads frames: values (frames x channels) and the
/// per-channel missing mask.
pub(super) fn channel_arrays(batch: &[PreparedTake]) -> (Vec<f32>, Vec<bool>) {
    let values: usize = batch.iter().map(|t| t.xyz.len()).sum();
    let mut samples = Vec::with_capacity(values);
    let mut mask = Vec::with_capacity(values);
    for t in batch {
        samples.extend_from_slice(&t.xyz);
        mask.extend(t.missing.iter().flat_map(|&m| [m, m, m]));
    }
    (samples, mask)
}

#[cfg(test)]
mod tests;
