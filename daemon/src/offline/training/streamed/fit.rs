//! Driving [`StreamFit`] on the pool: the whitening pass over prepared frames (both halves of
//! each batch whitened at once, pushed in frame order), the whitened frames kept as `f32` (the
//! first 16 MiB in memory, the rest spilled: [`super::whitened`]), and every FastICA iteration
//! one pass over them with both halves of each chunk accumulated at once and merged in order
//! (bit-identical whatever the thread count).

use anyhow::{Context, Result};
use ica_core::fit::{FastIcaParams, FitData, FitOutput, Pass, StreamFit};
use ica_core::whiten::{Moments, Whitener};
use rayon::ThreadPool;

use super::whitened::{Whitened, HELD_BYTES};
use crate::offline::progress::Progress;

/// Whitened frames read back at once.
const CHUNK_FRAMES: usize = 32_768;

/// Takes a batch of prepared frames: values and the per-channel mask, frames x channels each.
pub(super) type FrameBatch<'a> = dyn FnMut(&[f32], &[bool]) -> Result<()> + 'a;

/// Calls its argument with every prepared frame, in batches.
pub(super) type WhitenSource<'a> = dyn FnMut(&mut FrameBatch<'_>) -> Result<()> + 'a;

/// Work that needs the fitted whitening only: run on the pool during the whitening pass and the
/// restarts, which leave part of it idle.
pub(super) type Alongside<'a> = Box<dyn FnOnce(&Whitener) + Send + 'a>;

/// Fits `params` to the frames `source` gives, whose statistics are `moments`; runs
/// `alongside` once the whitening is fitted.
///
/// # Errors
/// What the fit refuses (see [`ica_core::FitError`]), reading the takes, or the spill file.
pub(super) fn fit(
    params: &FastIcaParams,
    moments: Moments,
    frames: usize,
    source: &mut WhitenSource<'_>,
    alongside: Alongside<'_>,
    pool: &ThreadPool,
    progress: &mut dyn Progress,
) -> Result<FitOutput> {
    let mut fit = StreamFit::new(params, moments.channels()).context("training failed")?;
    fit.handle_moments(moments).context("training failed")?;
    let whitener = fit.whitener().context("whitening is fitted")?.clone();
    let mut store = pool.in_place_scope(|s| {
        s.spawn(|_| alongside(&whitener));
        whiten_pass(&mut fit, &whitener, params, frames, source, pool, progress)
    })?;
    loop {
        match fit.poll_pass() {
            Pass::Update => {
                if fit.iterations() == 0 {
                    progress.step("FastICA over all frames", "iterations", None);
                }
                let empty = fit.update_accumulator()?;
                let mut acc = empty.clone();
                let map = |z: &[f32]| {
                    let mut part = empty.clone();
                    part.add_chunk(z)?;
                    Ok(part)
                };
                for_each_half(&mut store, pool, &map, &mut |part| Ok(acc.merge(part)?))?;
                fit.handle_update(acc).context("training failed")?;
                progress.advance(1);
            }
            Pass::Sources => {
                progress.step(
                    "components' statistics",
                    "frames",
                    Some(store.frames() as u64),
                );
                let empty = fit.source_moments()?;
                let mut sums = empty.clone();
                let map = |z: &[f32]| {
                    let mut part = empty.clone();
                    part.add_chunk(z)?;
                    Ok(part)
                };
                for_each_half(&mut store, pool, &map, &mut |part| Ok(sums.merge(part)?))?;
                progress.advance(store.frames() as u64);
                fit.handle_sources(sums).context("training failed")?;
            }
            Pass::Done => return Ok(fit.finish()?),
            pass => unreachable!("the streaming fit asked for {pass} after whitening"),
        }
    }
}

/// The whitening pass: every frame whitened, spilled, and offered to the restarts'
/// subsample; then the restarts.
fn whiten_pass(
    fit: &mut StreamFit,
    whitener: &Whitener,
    params: &FastIcaParams,
    frames: usize,
    source: &mut WhitenSource<'_>,
    pool: &ThreadPool,
    progress: &mut dyn Progress,
) -> Result<Whitened> {
    progress.step("whitening", "frames", Some(frames as u64));
    let (c, m) = (whitener.channels(), whitener.components());
    let mut sub = fit.subsample()?;
    let mut store = Whitened::new(m, CHUNK_FRAMES, HELD_BYTES)?;
    let mut narrow = Vec::<f32>::new();
    source(&mut |values, mask| {
        let n = values.len() / c;
        let mid = n / 2;
        // f64 for the restarts' subsample (as the in-memory fit sees it), f32 in the spill.
        let half = |range: std::ops::Range<usize>| -> Result<Vec<f64>> {
            let data = FitData::new(&values[range.start * c..range.end * c], c)?
                .with_missing(&mask[range.start * c..range.end * c])?;
            let (mut z, mut scratch) = (Vec::new(), Vec::new());
            whitener.whiten_into(&data, &mut z, &mut scratch)?;
            Ok(z)
        };
        let (left, right) = pool.join(|| half(0..mid), || half(mid..n));
        for z in [left?, right?] {
            sub.push(&z)?;
            narrow.clear();
            narrow.extend(z.iter().map(|&v| v as f32));
            store.push(&narrow)?;
        }
        progress.advance(n as u64);
        Ok(())
    })?;
    progress.step(
        &format!(
            "{} FastICA restarts on {} frames",
            params.get_restarts(),
            sub.frames_kept()
        ),
        "restarts",
        None,
    );
    // On the pool: the restarts run at once there, and --threads holds.
    pool.install(|| fit.handle_whitened(sub))
        .context("training failed")?;
    Ok(store)
}

/// One pass over the whitened frames: `map` on both halves of each chunk at once, `merge` on
/// the results in order.
fn for_each_half<T: Send>(
    store: &mut Whitened,
    pool: &ThreadPool,
    map: &(dyn Fn(&[f32]) -> Result<T> + Sync),
    merge: &mut dyn FnMut(T) -> Result<()>,
) -> Result<()> {
    let m = store.width();
    store.for_each_chunk(&mut |z| {
        let (left, right) = z.split_at((z.len() / m) / 2 * m);
        let (a, b) = pool.join(|| map(left), || map(right));
        merge(a?)?;
        merge(b?)
    })
}
