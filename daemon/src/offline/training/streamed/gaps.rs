//! Gap filling over the spilled frames: the rounds of [`ica_core::impute::fill_gaps`], each
//! one pass over the frames with gaps. The complete frames' moments are taken once (pass 2);
//! each round adds the filled frames' moments to them ([`Moments::merge_filled`]) and fits the
//! next model from the sum, so a round costs the gappy frames only.

use anyhow::{Context, Result};
use ica_core::fit::FitData;
use ica_core::impute::{GapFill, GapFiller, GapModel, EM_ITERATIONS};
use ica_core::whiten::{Components, Moments, Whitener};
use rayon::ThreadPool;

use super::collect::Collected;
use super::spill::f32_values;
use crate::offline::progress::Progress;

/// Frames read from the spill file at once.
const CHUNK_FRAMES: usize = 8192;

/// The gaps filled: the moments the fit whitens with, and the model that fills the gaps of a
/// prepared frame the same way (`None`: no frame has gaps to fill).
#[derive(Debug)]
pub(super) struct Filled {
    pub moments: Moments,
    pub model: Option<GapModel>,
    /// Channels seen in some frame (a gap on another one stays missing).
    pub seen: Vec<bool>,
    pub report: GapFill,
}

/// Runs the rounds (see the module docs).
///
/// # Errors
/// What whitening the complete frames fails with (too few of them, no variance), or the spill
/// file failing.
pub(super) fn fill(
    collected: &mut Collected,
    components: Components,
    pool: &ThreadPool,
    progress: &mut dyn Progress,
) -> Result<Filled> {
    let c = collected.channels;
    let seen: Vec<bool> = collected
        .moments
        .missing_everywhere()
        .iter()
        .map(|&m| !m)
        .collect();
    let gappy = collected.gappy.records();
    let report = GapFill {
        frames: gappy,
        samples: (0..c)
            .filter(|&ch| seen[ch])
            .map(|ch| collected.gap_missing[ch])
            .sum(),
        frames_left_out: collected.left_out,
    };
    if gappy == 0 {
        return Ok(Filled {
            moments: collected.moments.clone(),
            model: None,
            seen,
            report,
        });
    }
    let mut pca =
        Whitener::from_moments(&collected.moments, components).context("training failed")?;
    for round in 0..EM_ITERATIONS {
        progress.step(
            &format!("filling gaps, round {}/{EM_ITERATIONS}", round + 1),
            "frames",
            Some(gappy as u64),
        );
        let model = GapModel::from_whitener(&pca);
        let filled = filled_moments(collected, &model, &seen, pool, progress)?;
        let mut moments = collected.moments.clone();
        moments.merge_filled(filled)?;
        if round + 1 == EM_ITERATIONS {
            return Ok(Filled {
                moments,
                model: Some(model),
                seen,
                report,
            });
        }
        pca = Whitener::from_moments(&moments, components).context("training failed")?;
    }
    unreachable!("EM_ITERATIONS > 0: the last round returns")
}

/// Fills every spilled frame with `model` in place: `values` and `mask` are frames x channels;
/// a filled frame's mask keeps only the channels never seen.
pub(super) fn fill_frames(model: &GapModel, seen: &[bool], values: &mut [f32], mask: &mut [bool]) {
    let c = seen.len();
    let mut filler = model.filler();
    for (x, m) in values.chunks_exact_mut(c).zip(mask.chunks_exact_mut(c)) {
        fill_frame(&mut filler, seen, x, m);
    }
}

/// Fills one frame (see [`fill_frames`]).
pub(super) fn fill_frame(filler: &mut GapFiller<'_>, seen: &[bool], x: &mut [f32], m: &mut [bool]) {
    filler.fill(x, m);
    for (gone, &s) in m.iter_mut().zip(seen) {
        *gone &= !s;
    }
}

/// The moments of the spilled frames filled by `model`.
fn filled_moments(
    collected: &mut Collected,
    model: &GapModel,
    seen: &[bool],
    pool: &ThreadPool,
    progress: &mut dyn Progress,
) -> Result<Moments> {
    let c = collected.channels;
    let mut total = Moments::new(c);
    let (mut values, mut mask) = (Vec::new(), Vec::new());
    collected.gappy.for_each_chunk(CHUNK_FRAMES, &mut |bytes| {
        let frames = bytes.len() / (5 * c);
        values.clear();
        mask.clear();
        for record in bytes.chunks_exact(5 * c) {
            let mut x = Vec::new();
            f32_values(&record[..4 * c], &mut x);
            values.extend_from_slice(&x);
            mask.extend(record[4 * c..].iter().map(|&b| b != 0));
        }
        let mid = frames / 2;
        let (vl, vr) = values.split_at_mut(mid * c);
        let (ml, mr) = mask.split_at_mut(mid * c);
        let half = |v: &mut [f32], m: &mut [bool]| -> Result<Moments> {
            fill_frames(model, seen, v, m);
            let mut acc = Moments::new(c);
            acc.add_chunk(&FitData::new(&*v, c)?.with_missing(&*m)?)?;
            Ok(acc)
        };
        let (left, right) = pool.join(|| half(vl, ml), || half(vr, mr));
        total.merge(left?)?;
        total.merge(right?)?;
        progress.advance(frames as u64);
        Ok(())
    })?;
    Ok(total)
}
