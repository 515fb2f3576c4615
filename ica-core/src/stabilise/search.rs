//! Finding the head reference in a capture that names none: markers that are rigid among
//! themselves, that carry the head's motion and not the face's.
//!
//! 1. **Sample.** Up to [`SearchParams::max_frames`] frames, evenly over the takes, each with its
//!    two neighbours (for noise). Samples moving faster than 4 × the 99.9th percentile speed
//!    (at least 500 mm/s) are glitches (swaps, spikes) and left out; so are markers present in
//!    fewer than [`SearchParams::min_present`] of the sampled frames.
//! 2. **Noise.** The capture's own per-coordinate noise `σ`: the median over markers and axes
//!    of the robust spread of second differences, `1.4826 · MAD(x[t−1] − 2x[t] + x[t+1]) / √6`.
//! 3. **Pairs.** For every pair, its distance's robust spread beyond noise (the *excess*,
//!    `√(spread² − noise²)`), relative to its length (the *strain*), over
//!    [`PAIR_SAMPLES`] of the sampled triples. Optical systems measure a
//!    face-sized distance to better than [`RIGID_STRAIN`] (1 %); skin moves by several per cent
//!    (a brow raise stretches the forehead by 5-10 %, speech moves the jaw by 20 %).
//! 4. **Groups.** Candidate groups: every maximal set grown greedily from the most rigid pairs
//!    whose pairs all stay within the strain limit, and the greedy least-deforming set.
//! 5. **Assess** each candidate (`assess`): deformation, pose error at the face, head
//!    motion, and how much of its motion the face would inherit. Pruned first: every group
//!    (and its core) is assessed coarsely on [`COARSE_ASSESS_FRAMES`] frames against
//!    [`COARSE_ASSESS_OTHERS`] face markers, and only those [`choose`] could pick, with a
//!    margin, are assessed on the whole sample (at most [`SHORTLIST`] and the least leaking).
//!
//! [`choose`] then picks, among the candidates least tied to the face, the one with the
//! smallest pose error at the face.
//!
//! **Cost.** Bounded by the sample, whatever the session's length: at 109 markers, 5,886 pairs
//! and some 50 groups, a few tens of milliseconds on two cores (2.6 s before the pair table
//! was measured on a thin sample and the groups pruned; see `pairs` for why every pair is
//! measured). The decisions are those of every pair and group measured on 2,000 frames: the
//! same reference on Facial-Sing (its six root markers), AnimFace and the generator's head
//! bands, the same verdict on a still head (whose most head-like group, only named in the
//! report, may differ by a marker).

use rayon::prelude::*;

use super::assess::{assess_group, GroupAssessment, Scope};
use super::pairs::PairTable;
pub use super::pairs::PAIR_SAMPLES;
use super::sample::{MarkerFrames, Sample};
use crate::robust::median;

pub use super::assess::{MIN_MOTION_MM, MOTION_FACTOR, RIGID_NOISE_FACTOR};

/// Largest strain (excess spread / length) of a rigid pair. See the module docs.
pub const RIGID_STRAIN: f64 = 0.01;
/// A group whose pose explains at least this share of the other markers' motion in its own
/// coordinates is a part of the face (a forehead lifting with the brows), not the head.
pub const FACE_LEAKAGE: f64 = 0.6;
/// Candidates leaking at most twice the least leaking one (or this much more, if that is
/// more) compete on pose error. Leakage is a ratio: a group that drags the face leaks several
/// times what the head leaks (jaw 0.20 against 0.05 on a synthetic face), while where head
/// motion follows the expression every head-like group leaks alike (0.26 to 0.46 on
/// Facial-Sing).
pub const LEAKAGE_TOLERANCE: f64 = 0.05;
/// Knobs of [`search_reference`]; the defaults are the documented constants.
#[derive(Debug, Clone, PartialEq)]
pub struct SearchParams {
    /// Frames sampled at most (each with its two neighbours).
    pub max_frames: usize,
    /// Markers present in fewer than this share of the sampled frames are not candidates.
    pub min_present: f64,
    /// [`RIGID_STRAIN`].
    pub rigid_strain: f64,
    /// Candidate groups grown (from the most rigid pairs).
    pub max_groups: usize,
    /// Size of the least-deforming set when no rigid group exists.
    pub least_deforming: usize,
}

impl Default for SearchParams {
    fn default() -> SearchParams {
        SearchParams {
            max_frames: 1000,
            min_present: 0.8,
            rigid_strain: RIGID_STRAIN,
            max_groups: 40,
            least_deforming: 6,
        }
    }
}

/// What [`search_reference`] measured.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceSearch {
    /// The capture's noise per coordinate (mm).
    pub noise_mm: f64,
    /// Frames sampled.
    pub frames: usize,
    /// Samples left out as glitches.
    pub glitches: usize,
    /// Candidate groups, assessed, least leakage first.
    pub candidates: Vec<GroupAssessment>,
}

/// Which candidate [`choose`] took, and why.
#[derive(Debug, Clone, PartialEq)]
pub enum Choice {
    /// Stabilise on this group.
    Stabilise(GroupAssessment),
    /// The best group moves too little to be worth it.
    StillHead(GroupAssessment),
    /// Every candidate moves with the face.
    MovesWithFace(GroupAssessment),
    /// No candidate of three markers or more.
    NoCandidate,
}

/// Picks a head reference among assessed candidates: among the groups least tied to the face
/// (leakage below [`FACE_LEAKAGE`] and at most twice the least, see [`LEAKAGE_TOLERANCE`]),
/// the one with the smallest pose error at the face; stabilised only when the head's motion
/// is measurable.
///
/// Leakage decides first because a rigid part of the face (a jaw, a forehead lifting as a
/// block) can be as rigid as the head, but drags the face with it. Where head motion follows
/// the expression (singing), every candidate leaks about as much and the pose error decides.
pub fn choose(candidates: &[GroupAssessment]) -> Choice {
    let least = candidates
        .iter()
        .map(|c| c.leakage)
        .fold(f64::INFINITY, f64::min);
    let window = (2.0 * least).max(least + LEAKAGE_TOLERANCE);
    let head_like = candidates
        .iter()
        .filter(|c| c.leakage < FACE_LEAKAGE && c.leakage <= window)
        .min_by(|a, b| a.pose_error_mm.total_cmp(&b.pose_error_mm));
    match head_like {
        Some(best) if best.motion_is_measurable() => Choice::Stabilise(best.clone()),
        Some(best) => Choice::StillHead(best.clone()),
        None => match candidates.first() {
            Some(c) => Choice::MovesWithFace(c.clone()),
            None => Choice::NoCandidate,
        },
    }
}

/// Searches a capture for its head reference. See the module docs.
pub fn search_reference(frames: &MarkerFrames<'_>, params: &SearchParams) -> ReferenceSearch {
    let sample = Sample::draw(frames, params.max_frames);
    let candidates_markers: Vec<usize> = (0..frames.markers)
        .filter(|&m| sample.present_share(m) >= params.min_present)
        .collect();
    let noise_mm = sample.noise_mm(&candidates_markers);
    let pairs = PairTable::measure(&sample, &candidates_markers);
    // Grown at the strain limit and at a half and a quarter of it: a marker that barely moves
    // relative to a band (or moves across the lines to it, which distances hardly see) joins
    // the band at the loose limit but not at the tight ones.
    let sorted = pairs.sorted_pairs();
    let mut groups = Vec::new();
    for divisor in [4.0, 2.0, 1.0] {
        let limit = params.rigid_strain / divisor;
        for g in rigid_groups(&pairs, &sorted, limit, params.max_groups) {
            if !groups.contains(&g) {
                groups.push(g);
            }
        }
    }
    let ld = least_deforming(&pairs, &sorted, params.least_deforming);
    if ld.len() >= 3 && !groups.contains(&ld) {
        groups.push(ld);
    }
    let all_frames: Vec<usize> = (0..sample.frames()).map(|s| 3 * s + 1).collect();
    let full = Scope {
        frames: &all_frames,
        others: &candidates_markers,
    };
    let shortlist = shortlist(&sample, &groups, &candidates_markers, noise_mm);
    let mut candidates: Vec<GroupAssessment> = shortlist
        .par_iter()
        .filter_map(|group| assess_group(&sample, group, &full, noise_mm))
        .collect();
    candidates.sort_by(|a, b| a.leakage.total_cmp(&b.leakage));
    ReferenceSearch {
        noise_mm,
        frames: sample.frames(),
        glitches: sample.glitches,
        candidates,
    }
}

/// Frames of the sample the first, coarse assessment of every group fits.
pub const COARSE_ASSESS_FRAMES: usize = 128;
/// Other markers the coarse assessment measures the face by (evenly among the candidates).
pub const COARSE_ASSESS_OTHERS: usize = 32;
/// Groups assessed in full: the coarsely assessed ones [`choose`] could pick, by pose error.
pub const SHORTLIST: usize = 4;

/// The groups worth a full assessment. Every group (and its core, see [`core_of`]) is first
/// assessed on [`COARSE_ASSESS_FRAMES`] frames against [`COARSE_ASSESS_OTHERS`] markers;
/// those [`choose`] could pick with some margin on the leakage (its window widened by a
/// quarter and 0.02, the face limit by 0.05) go on, the [`SHORTLIST`] of least pose error and
/// always the least leaking one.
fn shortlist(
    sample: &Sample,
    groups: &[Vec<usize>],
    candidates: &[usize],
    noise_mm: f64,
) -> Vec<Vec<usize>> {
    let every = sample.frames().div_ceil(COARSE_ASSESS_FRAMES).max(1);
    let frames: Vec<usize> = (0..sample.frames())
        .step_by(every)
        .map(|s| 3 * s + 1)
        .collect();
    let coarse = |group: &Vec<usize>| {
        let others: Vec<usize> = candidates
            .iter()
            .copied()
            .filter(|m| !group.contains(m))
            .collect();
        let stride = others.len().div_ceil(COARSE_ASSESS_OTHERS).max(1);
        let others: Vec<usize> = others.into_iter().step_by(stride).collect();
        let scope = Scope {
            frames: &frames,
            others: &others,
        };
        assess_group(sample, group, &scope, noise_mm)
    };
    let mut assessed: Vec<GroupAssessment> = groups.par_iter().filter_map(coarse).collect();
    // A group grown to one marker too many (a face marker that barely moves relative to the
    // band) is assessed without its outliers too.
    let cores: Vec<Vec<usize>> = assessed
        .iter()
        .map(core_of)
        .filter(|core| core.len() >= 3 && !groups.contains(core))
        .collect();
    let mut seen: Vec<&Vec<usize>> = Vec::new();
    let cores: Vec<&Vec<usize>> = cores
        .iter()
        .filter(|c| {
            let new = !seen.contains(c) && assessed.iter().all(|a| &a.markers != *c);
            if new {
                seen.push(c);
            }
            new
        })
        .collect();
    assessed.extend(cores.into_par_iter().filter_map(coarse).collect::<Vec<_>>());
    pick_shortlist(&assessed)
}

/// Out of the coarse assessments, the groups [`shortlist`] passes on.
fn pick_shortlist(assessed: &[GroupAssessment]) -> Vec<Vec<usize>> {
    let least = assessed
        .iter()
        .map(|c| c.leakage)
        .fold(f64::INFINITY, f64::min);
    let window = 1.25 * (2.0 * least).max(least + LEAKAGE_TOLERANCE) + 0.02;
    let mut eligible: Vec<&GroupAssessment> = assessed
        .iter()
        .filter(|c| c.leakage < FACE_LEAKAGE + 0.05 && c.leakage <= window)
        .collect();
    eligible.sort_by(|a, b| a.pose_error_mm.total_cmp(&b.pose_error_mm));
    let mut chosen: Vec<Vec<usize>> = eligible
        .iter()
        .take(SHORTLIST)
        .map(|a| a.markers.clone())
        .collect();
    if let Some(a) = assessed
        .iter()
        .min_by(|a, b| a.leakage.total_cmp(&b.leakage))
    {
        if !chosen.contains(&a.markers) {
            chosen.push(a.markers.clone());
        }
    }
    chosen
}

/// A marker fitting its group's template worse than this many times the group's median is an
/// outlier of the group.
pub const CORE_RESIDUAL_FACTOR: f64 = 2.0;

/// The group without its outliers (see [`CORE_RESIDUAL_FACTOR`]).
fn core_of(a: &GroupAssessment) -> Vec<usize> {
    let mut sorted = a.marker_residual_mm.clone();
    let typical = median(&mut sorted);
    a.markers
        .iter()
        .zip(&a.marker_residual_mm)
        .filter(|(_, &r)| r <= CORE_RESIDUAL_FACTOR * typical)
        .map(|(&m, _)| m)
        .collect()
}

/// Assesses a given group (markers the user or a naming convention chose).
pub fn assess_named(frames: &MarkerFrames<'_>, markers: &[usize]) -> Option<GroupAssessment> {
    let sample = Sample::draw(frames, SearchParams::default().max_frames);
    let all: Vec<usize> = (0..frames.markers)
        .filter(|&m| sample.present_share(m) > 0.0)
        .collect();
    let noise_mm = sample.noise_mm(&all);
    let all_frames: Vec<usize> = (0..sample.frames()).map(|s| 3 * s + 1).collect();
    let scope = Scope {
        frames: &all_frames,
        others: &all,
    };
    assess_group(&sample, markers, &scope, noise_mm)
}

/// Maximal groups within `limit`, each grown from one of the most rigid pairs (`sorted`: the
/// pairs by increasing strain) by adding the marker closest (in mean strain) to the group
/// while every pair stays rigid.
fn rigid_groups(
    pairs: &PairTable,
    sorted: &[(usize, usize)],
    limit: f64,
    max_groups: usize,
) -> Vec<Vec<usize>> {
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let seeds = sorted
        .iter()
        .copied()
        .take_while(|&(i, j)| pairs.strain(i, j) <= limit)
        .take(max_groups);
    for (i, j) in seeds {
        let mut group = vec![i, j];
        loop {
            let next = (0..pairs.len())
                .filter(|c| !group.contains(c))
                .filter(|&c| group.iter().all(|&g| pairs.strain(c, g) <= limit))
                .min_by(|&a, &b| {
                    pairs
                        .mean_strain(a, &group)
                        .total_cmp(&pairs.mean_strain(b, &group))
                });
            match next {
                Some(c) => group.push(c),
                None => break,
            }
        }
        let markers = pairs.to_markers(&group);
        if markers.len() >= 3 && !groups.contains(&markers) {
            groups.push(markers);
        }
    }
    groups
}

/// The `count` markers grown greedily from the most rigid pair by least mean strain, whatever
/// the strain (`sorted`: the pairs by increasing strain): the fallback when nothing is rigid.
fn least_deforming(pairs: &PairTable, sorted: &[(usize, usize)], count: usize) -> Vec<usize> {
    let Some(&(i, j)) = sorted.first() else {
        return Vec::new();
    };
    let mut group = vec![i, j];
    while group.len() < count.min(pairs.len()) {
        let next = (0..pairs.len())
            .filter(|c| !group.contains(c))
            .map(|c| (c, pairs.mean_strain(c, &group)))
            .filter(|(_, s)| s.is_finite())
            .min_by(|a, b| a.1.total_cmp(&b.1));
        match next {
            Some((c, _)) => group.push(c),
            None => break,
        }
    }
    pairs.to_markers(&group)
}

#[cfg(test)]
mod tests;
