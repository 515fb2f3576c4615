//! Training on sessions of any length in bounded memory: takes read one at a time, in
//! batches prepared on a thread pool, never all held.
//!
//! 1. [`scan`]: every take read once: the rate, frame counts, which markers stay, and a
//!    bounded sample ([`SAMPLE_FRAMES`]) the head reference, its template and the glitch
//!    limits are learned from ([`super::capture::learn`], as the in-memory path learns them
//!    from every frame). A session of at most [`IN_MEMORY_FRAMES`] frames is kept and trained
//!    in memory instead ([`super::train`]: identical results; streaming is no slower at that
//!    length, and faster on long sessions of many markers).
//! 2. [`collect`]: every frame prepared once: the moments, the frames with gaps (spilled),
//!    the glitch counts and what the quality report measures. A session the sample holds
//!    whole is not stabilised again: the glitch checks run on the frames step 1 put in head
//!    coordinates for the glitch limits.
//! 3. [`gaps`]: the gap-filling rounds over the spilled frames only.
//! 4. [`fit`]: the prepared frames read back, gaps filled, whitened and spilled; the restarts
//!    on the subsample drawn during that pass; FastICA over the whitened spill, one pass per
//!    iteration.
//!
//! Memory: one batch of takes ([`BATCH_FRAMES`] frames, or one take if longer), the sample,
//! the covariance and the model, the quality report's bounded samples and at most 16 MiB of
//! whitened frames; never a copy of the session. Both halves of every batch and chunk run at
//! once on the pool, and partial sums are merged in a fixed order, so the model is the same
//! with one thread or several.

mod collect;
mod finish;
mod fit;
mod gaps;
mod noise;
mod read;
mod sample;
mod scan;
mod spill;
mod whitened;

use std::collections::BTreeMap;

use anyhow::{Context, Result};
use ica_core::measure::{slow_residual_of_means, Reconstruction, ResidualSums};
use rayon::ThreadPool;

use super::capture::{self, RefResiduals};
use super::model::{capped_at_noise, component_params};
use super::{Stage, TrainOptions, Trained};
use crate::offline::progress::Progress;
use crate::offline::{LoadedTake, TakeInput};
use collect::Collected;
use finish::{fitted_model, measured, prep_report};
use rayon::prelude::*;
use read::{batches, Stabilised, TakePrep};

/// Sessions of at most this many frames (half a minute at 120 Hz) train in memory. Measured
/// with `train --components 20` on synthetic sessions: 3,531 frames take 0.24-0.28 s either
/// way; 7,751 frames 0.39-0.42 s in memory against 0.34-0.39 s streamed; 12,172 frames
/// 0.47-0.50 s against 0.42-0.43 s; 75,719 frames 2.3-2.5 s against 1.3-1.6 s. On real
/// captures the two are on a par above the limit: Facial-Sing four times over (12,000
/// frames, 37 markers) 0.60-0.63 s in memory against 0.57-0.66 s streamed, the AnimFace
/// takes three times over (7,476 frames, 41 markers) 0.56-0.67 s against 0.58-0.70 s; the
/// models agree within 1e-7.
pub const IN_MEMORY_FRAMES: usize = 4_000;
/// Frames the head and the glitch limits are learned from at most (about 3 minutes at 120 Hz,
/// in stretches of 2 s spread over the session).
pub const SAMPLE_FRAMES: usize = 20_000;
/// Frames of takes prepared at once.
const BATCH_FRAMES: u64 = 16_384;
/// Prepared frames read back at once in the passes after the statistics (gaps, whitening):
/// 2.6 MB of values at 315 channels, which stay in the cache while both halves are whitened.
/// Against [`BATCH_FRAMES`] (one 15 MB read at 12,308 frames) the whitening step of the
/// unnamed bench layout went from 0.051-0.058 s to 0.040-0.044 s; at 4 hours it is
/// unchanged (2.8 s). Every frame is whitened alone, so the model does not change.
const WHITEN_FRAMES: usize = 2_048;
/// How training decodes C3D takes: by emoshift's own decoder alone. Decoding through c3dio as
/// well and comparing (what `inspect` and the other commands do) cost a tenth of a train (1 h
/// session: 8.86 s against 8.05 s), and where the two disagree the reader keeps our values.
const DECODING: replay::C3dDecoding = replay::C3dDecoding::Own;

/// How streaming training runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StreamOptions {
    /// Threads of the pool (0: one per core).
    pub threads: usize,
    /// Stream even a session short enough to train in memory.
    pub always_stream: bool,
    /// Sessions of at most this many frames train in memory (`None`: [`IN_MEMORY_FRAMES`]).
    pub hold_frames: Option<usize>,
}

/// Trains a model on `takes` (each cut to its range), streaming them unless the session is short (see
/// the module docs).
///
/// # Errors
/// An unreadable take, preparation or the fit refusing the data, a spill file failing, or a
/// fitted model that fails validation.
pub fn train_files(
    takes: &[TakeInput],
    options: &TrainOptions,
    stream: &StreamOptions,
    progress: &mut dyn Progress,
) -> Result<Trained> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(stream.threads)
        .build()
        .context("cannot start the training threads")?;
    let hold = if stream.always_stream {
        0
    } else {
        stream.hold_frames.unwrap_or(IN_MEMORY_FRAMES)
    };
    let mut scanned = scan::scan(takes, &options.prep, hold, SAMPLE_FRAMES, &pool, progress)?;
    if scanned.held.is_none() && scanned.total_frames() <= hold {
        // The scan guessed the session long from its files' sizes: read it again to hold it,
        // so which path trains a session depends on its frames only.
        progress.step("reading takes again to hold them", "takes", None);
        let held = takes
            .iter()
            .map(|t| {
                Ok(LoadedTake {
                    path: t.path.clone(),
                    take: t.load(DECODING)?,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        scanned.held = Some(held);
    }
    if let Some(takes) = &scanned.held {
        let mut stage = |s: Stage| match s {
            Stage::Preparing => progress.step("preparing in memory", "takes", None),
            Stage::Fitting { restarts } => progress.step(
                &format!("whitening and FastICA ({restarts} restarts) in memory"),
                "restarts",
                None,
            ),
        };
        // On the pool, so the restarts keep to --threads.
        return pool.install(|| super::train(takes, options, &mut stage));
    }
    streamed(scanned, options, &pool, progress)
}

fn streamed(
    scanned: scan::Scan,
    options: &TrainOptions,
    pool: &ThreadPool,
    progress: &mut dyn Progress,
) -> Result<Trained> {
    let (learned, head_frames) = learn(&scanned, options, pool, progress)?;
    let total = scanned.total_frames();
    let (scanned, raw) = scanned.take_raw()?;
    let (mut collected, head_residuals) =
        statistics(&scanned, raw, &learned, head_frames, pool, progress)?;
    let noise_mm = pool.install(|| collected.noise.noise_mm());
    let params = component_params(options, noise_mm);
    // Pass 3: the gaps.
    let filled = gaps::fill(&mut collected, params.get_components(), pool, progress)?;
    // Pass 4: the prepared frames, gaps filled, whitened; then FastICA over the spill.
    let (prepared, c) = (&mut collected.prepared, collected.channels);
    let mut source = |each: &mut fit::FrameBatch<'_>| {
        collect::for_each_prepared(prepared, c, WHITEN_FRAMES, &mut |values, mask| {
            if let Some(model) = &filled.model {
                fill_batch(model, &filled.seen, values, mask, pool);
            }
            each(values, mask)
        })
    };
    // The report's residuals need only the subspace the model will span: measured from the
    // whitening while the pool has room.
    let (frames, means) = (&collected.residual_frames, &collected.slow_means);
    let mut residuals = None;
    let alongside: fit::Alongside<'_> = Box::new(|whitener| {
        residuals = Some(residual_measures(whitener, frames, means, c, pool));
    });
    let fit = fit::fit(
        &params,
        filled.moments,
        total,
        &mut source,
        alongside,
        pool,
        progress,
    )?;
    progress.finish();
    let residuals = residuals.context("the residuals were measured alongside the fit")?;
    let (head, measures) = measured(&learned, head_residuals, residuals, noise_mm);
    let model = fitted_model(&scanned, &learned, fit, (&head, measures), options)?;
    let capped_at_noise = capped_at_noise(&params, &model);
    let data = prep_report(scanned, learned, &collected, &model, head);
    Ok(Trained {
        model,
        data,
        gaps: filled.report,
        noise_mm,
        capped_at_noise,
    })
}

/// The head reference, then the glitch limits, learned from the scan's sample: two steps, so
/// the head decision's time is reported apart. With the sample in the decided head's
/// coordinates when it is the whole session (just stabilised: the statistics pass reuses it).
fn learn(
    scanned: &scan::Scan,
    options: &TrainOptions,
    pool: &ThreadPool,
    progress: &mut dyn Progress,
) -> Result<(capture::Learned, Option<capture::HeadFrames>)> {
    let (sample, labels, prep) = (&scanned.sample, &scanned.labels, &options.prep);
    progress.step("deciding the head", "frames", None);
    let decided = pool.install(|| capture::decide_head(sample, labels, &scanned.excluded, prep))?;
    progress.step("learning the glitch limits", "frames", None);
    let (n, rate_hz) = (labels.len(), scanned.rate_hz);
    let (learned, head_frames) =
        pool.install(|| capture::learn_limits(sample, n, rate_hz, prep, decided))?;
    Ok((learned, scanned.sample_is_session().then_some(head_frames)))
}

/// Each marker's RMS residual over the residual frames (`channels` values each), and the slow
/// residual of the blocks' means, against `model`'s reconstruction. The residual's two halves
/// and the slow residual run at once; the halves are fixed, so the sums do not depend on the
/// thread count.
fn residual_measures(
    model: &impl Reconstruction,
    frames: &[f32],
    means: &[Vec<f64>],
    channels: usize,
    pool: &ThreadPool,
) -> (Vec<f64>, Option<(f64, usize)>) {
    let c = channels;
    let (left, right) = frames.split_at(frames.len() / c / 2 * c);
    let ((mut sums, right), slow_residual) = pool.join(
        || {
            pool.join(
                || ResidualSums::of(model, left.chunks_exact(c)),
                || ResidualSums::of(model, right.chunks_exact(c)),
            )
        },
        || slow_residual_of_means(model, means),
    );
    sums.add(&right);
    (sums.rms(), slow_residual)
}

/// A batch prepared and not yet collected: its index and its takes.
type Prepared = Option<(usize, Vec<read::PreparedTake>)>;

/// How the scanned takes are prepared, with what was learned from the sample.
fn take_prep<'a>(
    scanned: &'a scan::Scan,
    learned: &'a capture::Learned,
    stabilised: Option<Stabilised<'a>>,
) -> TakePrep<'a> {
    TakePrep {
        kept: &scanned.kept,
        spilled_markers: scanned.first_markers,
        rate_hz: scanned.rate_hz,
        capture: &learned.capture,
        stabilised,
    }
}

/// The takes in batches of about [`BATCH_FRAMES`] frames, and each batch's frames.
fn take_batches(frames: &[usize]) -> (Vec<std::ops::Range<usize>>, Vec<usize>) {
    let sizes: Vec<u64> = frames.iter().map(|&f| f as u64).collect();
    let batches = batches(&sizes, BATCH_FRAMES);
    let groups = batches
        .iter()
        .map(|r| frames[r.clone()].iter().sum())
        .collect();
    (batches, groups)
}

/// Where each take of a batch starts in its bytes (`record` bytes a frame), and where the
/// last ends.
fn take_starts(frames: &[usize], record: usize) -> Vec<usize> {
    let mut starts = vec![0];
    for &f in frames {
        starts.push(starts.last().copied().unwrap_or(0) + f * record);
    }
    starts
}

/// A session the sample holds whole as the statistics pass reads it ([`Stabilised`]); its
/// stabilisation residuals offered to `collected` at once, in the order the takes would.
fn stabilised<'a>(
    head_frames: Option<&'a capture::HeadFrames>,
    scanned: &'a scan::Scan,
    collected: &mut Collected,
) -> Option<Stabilised<'a>> {
    let frames = head_frames?;
    collected.residuals.extend(&frames.residuals);
    Some(Stabilised {
        frames,
        takes: &scanned.sample,
        starts: take_starts(&scanned.take_frames, 1),
    })
}

/// Pass 2: every spilled frame prepared (or only checked for glitches, when `head_frames`
/// holds the session stabilised) and collected; each reference marker's residual.
fn statistics(
    scanned: &scan::Scan,
    mut raw: spill::Spill,
    learned: &capture::Learned,
    head_frames: Option<capture::HeadFrames>,
    pool: &ThreadPool,
    progress: &mut dyn Progress,
) -> Result<(Collected, Option<BTreeMap<String, f64>>)> {
    let (total, frames) = (scanned.total_frames(), &scanned.take_frames);
    progress.step("statistics", "frames", Some(total as u64));
    // The prepared frames go over the raw ones: each batch is collected after it was read.
    let mut collected = Collected::new(scanned.labels.len(), frames, scanned.rate_hz, &mut raw)?;
    let mut refs = learned.capture.head.as_ref().map(RefResiduals::new);
    let stabilised = stabilised(head_frames.as_ref(), scanned, &mut collected);
    let prep = take_prep(scanned, learned, stabilised);
    let (batches, groups) = take_batches(frames);
    let record = 13 * scanned.first_markers;
    // Each batch is prepared on the pool while the previous one is collected here, so the
    // pool does not wait for the collecting (which writes the prepared spill).
    let mut pending: Prepared = None;
    let mut collect = |pending: Prepared,
                       collected: &mut Collected,
                       refs: &mut Option<RefResiduals<'_>>|
     -> Result<()> {
        if let Some((b, batch)) = pending {
            collected.add_batch(&batch, refs.as_mut(), pool)?;
            progress.advance(groups[b] as u64);
        }
        Ok(())
    };
    raw.for_each_group(&groups, &mut |b, bytes| {
        let starts = take_starts(&frames[batches[b].clone()], record);
        let prepare = || {
            pool.install(|| {
                starts
                    .par_windows(2)
                    .enumerate()
                    .map(|(k, w)| prep.prepare(batches[b].start + k, &bytes[w[0]..w[1]]))
                    .collect::<Result<Vec<_>>>()
            })
        };
        let previous = pending.take();
        let (batch, done) = std::thread::scope(|s| {
            let batch = s.spawn(prepare);
            let done = collect(previous, &mut collected, &mut refs);
            (batch.join(), done)
        });
        done?;
        let batch = batch.map_err(|_| anyhow::anyhow!("a take preparation panicked"))??;
        pending = Some((b, batch));
        Ok(())
    })?;
    collect(pending, &mut collected, &mut refs)?;
    drop(raw);
    collected.prepared.trim()?;
    let residuals = refs.map(|r| r.by_label(&scanned.labels));
    Ok((collected, residuals))
}

/// Fills the gaps of a batch's frames that have some (as [`collect`] spilled them).
fn fill_batch(
    model: &ica_core::impute::GapModel,
    seen: &[bool],
    values: &mut [f32],
    mask: &mut [bool],
    pool: &ThreadPool,
) {
    use ica_core::impute::{frame_gaps, FrameGaps};
    let c = seen.len();
    let fill = |v: &mut [f32], m: &mut [bool]| {
        let mut filler = model.filler();
        for (x, g) in v.chunks_exact_mut(c).zip(m.chunks_exact_mut(c)) {
            if frame_gaps(g) == FrameGaps::Fill {
                gaps::fill_frame(&mut filler, seen, x, g);
            }
        }
    };
    let mid = values.len() / c / 2 * c;
    let (vl, vr) = values.split_at_mut(mid);
    let (ml, mr) = mask.split_at_mut(mid);
    pool.join(|| fill(vl, ml), || fill(vr, mr));
}
