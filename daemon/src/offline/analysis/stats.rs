//! The analysis as an accumulator: groups of projected takes go in (a sentence's takes, or the
//! whole session at once), the [`Report`] comes out. Between groups it keeps only O(m) numbers
//! per take and per pair plus the m x m moments of [`ComponentMoments`], so a session of hours
//! is measured holding one sentence's takes (issue 18).
//!
//! Pairs are formed within a group, so every take of a sentence must be in the same group.
//! The numbers do not depend on how the session is grouped, except for the order of the
//! floating-point sums when the groups do not follow the manifest's order; takes and pairs are
//! reported in manifest order either way.

use std::collections::BTreeMap;

use anyhow::Result;
use ica_core::interpret::{
    self, ComponentMoments, EmotionDistanceAcc, LabelRules, LevelDistanceAcc,
};
use ica_core::model::Role;

use super::advice;
use super::space::{self, EmotionSpace, TakeLevel};
use super::{ComponentReport, Inputs, PairSummary, Report, TakeSummary};
use super::{DTW_BAND_SHARE, ROLE_REGIONS};

/// One projected take handed to [`SessionStats::add_group`].
#[derive(Debug, Clone, Copy)]
pub struct TakeSeries<'a> {
    /// Position in the manifest: orders the report's takes and pairs.
    pub index: usize,
    /// File, as the manifest names it.
    pub file: &'a str,
    /// Sentence id.
    pub sentence: &'a str,
    /// Emotion name.
    pub emotion: &'a str,
    /// Components over the take, frames x m.
    pub series: &'a [f64],
}

/// What is kept of a take once its series is dropped.
#[derive(Debug)]
struct TakeRecord {
    index: usize,
    summary: TakeSummary,
    /// The means the emotion space tests ([`take_means`]).
    level: Vec<f64>,
    /// Its offset from the first take of its sentence in the group, over DTW-aligned frames
    /// (zeros for that take; `None` when its sentence has no other take).
    aligned: Option<Vec<f64>>,
}

/// The analysis of a session so far; see the module docs.
#[derive(Debug)]
pub struct SessionStats {
    m: usize,
    band: usize,
    emotion: EmotionDistanceAcc,
    level: LevelDistanceAcc,
    moments: ComponentMoments,
    takes: Vec<TakeRecord>,
    /// Manifest indices of each pair, with its summary.
    pairs: Vec<((usize, usize), PairSummary)>,
}

impl SessionStats {
    /// Nothing seen yet, `m` components; `longest` is the frame count of the session's longest
    /// take, which sets the DTW band of every pair ([`DTW_BAND_SHARE`]), so it must be known
    /// before the first pair.
    pub fn new(m: usize, longest: usize) -> Self {
        let band = ((longest as f64) * DTW_BAND_SHARE).ceil() as usize;
        Self {
            m,
            band,
            emotion: EmotionDistanceAcc::new(m, Some(band)),
            level: LevelDistanceAcc::new(m),
            moments: ComponentMoments::new(m),
            takes: Vec::new(),
            pairs: Vec::new(),
        }
    }

    /// Adds a group of takes, in manifest order, and every pair within it (same sentence,
    /// different emotions).
    ///
    /// # Errors
    /// A metric that cannot be computed (bad shapes, non-finite components).
    pub fn add_group(&mut self, takes: &[TakeSeries<'_>]) -> Result<()> {
        let m = self.m;
        let first = self.takes.len();
        let mut means = Vec::with_capacity(takes.len());
        for t in takes {
            self.moments.add_series(t.series)?;
            let component_means = interpret::series_means(t.series, m)?;
            means.push(component_means.clone());
            self.takes.push(TakeRecord {
                index: t.index,
                summary: TakeSummary {
                    file: t.file.to_string(),
                    sentence: t.sentence.to_string(),
                    emotion: t.emotion.to_string(),
                    frames: t.series.len() / m,
                    component_means,
                },
                level: take_means(t.series, m),
                aligned: None,
            });
        }
        // Each take's offset is taken against the first take of its sentence in the group.
        let reference: Vec<usize> = takes
            .iter()
            .map(|t| {
                takes
                    .iter()
                    .position(|r| r.sentence == t.sentence)
                    .expect("a take is in its own group")
            })
            .collect();
        for (i, a) in takes.iter().enumerate() {
            for (j, b) in takes.iter().enumerate().skip(i + 1) {
                if a.sentence != b.sentence || a.emotion == b.emotion {
                    continue;
                }
                let pair = self.emotion.add_pair(a.series, b.series)?;
                if reference[j] == i {
                    self.takes[first + j].aligned = Some(pair.offset);
                }
                self.level.add_means(&means[i], &means[j])?;
                let summary = PairSummary {
                    sentence: a.sentence.to_string(),
                    a: (a.file.to_string(), a.emotion.to_string()),
                    b: (b.file.to_string(), b.emotion.to_string()),
                    aligned_samples: pair.samples,
                };
                self.pairs.push(((a.index, b.index), summary));
            }
        }
        self.align_rest(takes, &reference, first)
    }

    /// Offsets of the takes the pairs did not align against their reference: the reference
    /// itself (zeros, once its sentence has another take) and takes in its emotion.
    fn align_rest(
        &mut self,
        takes: &[TakeSeries<'_>],
        reference: &[usize],
        first: usize,
    ) -> Result<()> {
        for (j, t) in takes.iter().enumerate() {
            let r = reference[j];
            if self.takes[first + j].aligned.is_some() {
                continue;
            }
            let paired = (0..takes.len()).any(|k| k != j && reference[k] == r);
            if !paired {
                continue;
            }
            let offset = if r == j {
                vec![0.0; self.m]
            } else {
                interpret::aligned_offset(takes[r].series, t.series, self.m, Some(self.band))?
            };
            self.takes[first + j].aligned = Some(offset);
        }
        Ok(())
    }

    /// The report over every group added.
    ///
    /// # Errors
    /// A region metric that cannot be computed (a region outside the model).
    pub fn finish(
        mut self,
        inputs: &Inputs<'_>,
        regions: &BTreeMap<String, Vec<usize>>,
    ) -> Result<Report> {
        let m = self.m;
        let model = inputs.model;
        self.takes.sort_by_key(|t| t.index);
        self.pairs.sort_by_key(|p| p.0);
        let measured = !self.pairs.is_empty();
        let d_emotion = measured.then(|| self.emotion.finish().per_component);
        let d_level = measured.then(|| self.level.finish());
        let space = measured.then(|| space_of(&self.takes, m, &model.quality().stability));
        // Region metrics and roles treat the emotion axes as the emotion set; components that
        // only shift a little with emotion keep their region role.
        let emotion = space.as_ref().map(|s| s.axes.clone()).unwrap_or_default();
        let d_region = region_distances(&self.moments, model, regions, &emotion)?;
        let rules = LabelRules::default();
        let roles = roles(m, &emotion, &d_region, &rules);
        let components = (0..m)
            .map(|k| ComponentReport {
                index: k,
                role: roles[k],
                d_emotion: d_emotion.as_ref().map(|d| d[k]),
                d_level: d_level.as_ref().map(|d| d[k]),
                d_region: d_region.iter().map(|(n, d)| (n.clone(), d[k])).collect(),
                mixing_norm_mm: model.mixing().column(k).norm(),
                emotion_effect: space.as_ref().map(|s| s.effects[k]),
            })
            .collect();
        let takes: Vec<TakeSummary> = self.takes.into_iter().map(|t| t.summary).collect();
        let near_misses = space.as_ref().map(advice::near_misses).unwrap_or_default();
        let sentences_per_emotion = advice::sentences_per_emotion(&takes);
        Ok(Report {
            advice: advice::lines(space.as_ref(), &near_misses, sentences_per_emotion),
            near_misses,
            sentences_per_emotion,
            model: inputs.model_path.display().to_string(),
            manifest: inputs.manifest_path.display().to_string(),
            components,
            emotion_note: emotion_note(space.as_ref(), emotion.is_empty(), m),
            emotion_components: emotion,
            emotion_measured: measured,
            levels: levels_of(space.as_ref()),
            space,
            pairs: self.pairs.into_iter().map(|(_, p)| p).collect(),
            takes,
            thresholds: rules,
            dtw_band_share: DTW_BAND_SHARE,
            regions: region_labels(model, regions),
            quality: model.quality().clone(),
        })
    }
}

/// The emotion space of the takes' levels, with its conditioning given each component's
/// `stability` across training restarts.
fn space_of(takes: &[TakeRecord], m: usize, stability: &[f64]) -> EmotionSpace {
    let levels: Vec<TakeLevel> = takes
        .iter()
        .map(|t| TakeLevel {
            sentence: t.summary.sentence.clone(),
            emotion: t.summary.emotion.clone(),
            means: t.level.clone(),
            aligned: t.aligned.clone(),
        })
        .collect();
    let mut space = space::emotion_space(&levels, m);
    space.conditioning = Some(space::conditioning(&space, &levels, stability));
    space
}

/// Roles from the region metrics, given the emotion set.
fn roles(
    m: usize,
    emotion: &[usize],
    d_region: &BTreeMap<String, Vec<f64>>,
    rules: &LabelRules,
) -> Vec<Role> {
    let role_inputs: Vec<(Role, &[f64])> = ROLE_REGIONS
        .iter()
        .filter_map(|(name, role)| d_region.get(*name).map(|d| (*role, d.as_slice())))
        .collect();
    interpret::label(m, emotion, &role_inputs, rules)
}

/// Level of the main emotion component per emotion name (empty without one).
fn levels_of(space: Option<&EmotionSpace>) -> BTreeMap<String, f64> {
    let Some(sp) = space else {
        return BTreeMap::new();
    };
    match sp.components.iter().position(|&k| Some(k) == sp.main) {
        Some(at) => sp
            .points
            .iter()
            .map(|(n, p)| (n.clone(), p.level[at]))
            .collect(),
        None => BTreeMap::new(),
    }
}

/// Error degrees of freedom under which a session is too small for the emotion test to
/// find more than a very large effect: say so rather than that there is none.
const FEW_ERROR_DF: usize = 4;

/// Why emotion was not measured or has no component (empty when it has), with the
/// strongest effect's numbers when none passed.
fn emotion_note(space: Option<&EmotionSpace>, no_component: bool, m: usize) -> String {
    let Some(space) = space else {
        return "emotion not measured: the manifest has no pair of takes with the same sentence \
                in two different emotions"
            .to_string();
    };
    if !no_component {
        return String::new();
    }
    let test = format!(
        "F test at p < {} over {m} components",
        interpret::EMOTION_ALPHA
    );
    let strongest = space
        .effects
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.f.total_cmp(&b.1.f));
    let Some((k, e)) = strongest.filter(|(_, e)| e.f > 0.0) else {
        return format!("no component's take levels differ between emotions ({test})");
    };
    let numbers = format!(
        "the strongest, c{k}, has F = {}, p = {:.2e} on {} error degrees of freedom",
        super::space::f_text(e.f),
        e.p,
        e.df_error
    );
    if e.df_error < FEW_ERROR_DF {
        format!(
            "too few takes to tell which components carry emotion ({test}): {numbers}; record \
             more sentences in each emotion"
        )
    } else {
        format!(
            "no component's take levels differ between emotions ({test}): {numbers}; no \
             component is labelled emotion"
        )
    }
}

/// The mean of each component over a take (frames x m series), as the emotion space tests it.
fn take_means(series: &[f64], m: usize) -> Vec<f64> {
    let frames = (series.len() / m.max(1)).max(1) as f64;
    let mut means = vec![0.0; m];
    for row in series.chunks_exact(m) {
        for (acc, v) in means.iter_mut().zip(row) {
            *acc += v / frames;
        }
    }
    means
}

/// Each region's metric per component (Eq. 4 of the method), the emotion axes taken as
/// the emotion set.
fn region_distances(
    moments: &ComponentMoments,
    model: &ica_core::model::IcaModel,
    regions: &BTreeMap<String, Vec<usize>>,
    emotion: &[usize],
) -> Result<BTreeMap<String, Vec<f64>>> {
    regions
        .iter()
        .map(|(name, markers)| {
            let d = moments.region_distance(model.mixing(), markers, emotion)?;
            Ok((name.clone(), d))
        })
        .collect()
}

/// Each region's marker labels.
fn region_labels(
    model: &ica_core::model::IcaModel,
    regions: &BTreeMap<String, Vec<usize>>,
) -> BTreeMap<String, Vec<String>> {
    regions
        .iter()
        .map(|(n, idx)| {
            let labels = idx.iter().map(|&i| model.labels()[i].clone()).collect();
            (n.clone(), labels)
        })
        .collect()
}
