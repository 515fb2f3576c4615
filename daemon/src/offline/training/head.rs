//! Deciding the head reference of a capture, in order:
//!
//! 1. markers the user names (`--head-reference`, the regions file's `head_reference`);
//! 2. markers with a common head-marker name ([`DEFAULT_HEAD_PATTERNS`], case-insensitive
//!    globs; `--head-patterns` replaces them);
//! 3. the capture's geometry ([`ica_core::stabilise::search`]): a group rigid among itself that
//!    moves as a head, or else the least-deforming markers, with a warning.
//!
//! Whatever the source, the head's motion is measured first: a head that does not move
//! measurably is not stabilised (stabilising would only add the pose estimate's noise), and a
//! group whose pose explains most of the face's own motion (a forehead lifting with the brows)
//! is never the head. Every decision comes back as a [`HeadReport`] with its numbers.

use anyhow::{anyhow, bail, Result};
use globset::{GlobBuilder, GlobSetBuilder};
use ica_core::quality::HeadReport;
use ica_core::stabilise::{
    assess_named, choose, search_reference, Choice, GroupAssessment, MarkerFrames, SearchParams,
    MIN_MOTION_MM, MOTION_FACTOR,
};
use replay::session::{Regions, SessionError};

/// Common names of rigid head markers: Vicon Plug-in Gait's head band, and head, hat, helmet
/// and head-rig markers of other setups.
pub const DEFAULT_HEAD_PATTERNS: [&str; 7] =
    ["LFHD", "RFHD", "LBHD", "RBHD", "head*", "hat*", "helmet*"];

/// How the head reference is chosen.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum HeadChoice {
    /// No stabilisation.
    None,
    /// Common head-marker names ([`DEFAULT_HEAD_PATTERNS`] or these patterns), then geometry.
    Auto {
        /// Name patterns tried before geometry.
        patterns: Vec<String>,
    },
    /// These labels or glob patterns (as in a regions file), named by the user.
    Labels {
        /// Labels or glob patterns.
        patterns: Vec<String>,
        /// Asked for on the command line (a regions file only describes the layout): not
        /// using them is a warning ([`HeadReport::requested`]).
        requested: bool,
    },
}

impl HeadChoice {
    /// Automatic, with the default name patterns.
    pub fn auto() -> HeadChoice {
        HeadChoice::Auto {
            patterns: DEFAULT_HEAD_PATTERNS
                .iter()
                .map(|p| p.to_string())
                .collect(),
        }
    }
}

/// The decision: reference markers (empty: no stabilisation), their template and the report.
#[derive(Debug, Clone)]
pub struct HeadDecision {
    /// Marker indices to stabilise on; empty when not stabilising.
    pub markers: Vec<usize>,
    /// The reference's shape (centred, mm, in `markers` order) as the decision's own
    /// Procrustes fit over its sample found it; empty when not stabilising.
    pub template: Vec<[f64; 3]>,
    /// What was decided and why.
    pub report: HeadReport,
}

impl HeadDecision {
    /// Not stabilising, for this reason.
    fn none(report: HeadReport) -> HeadDecision {
        HeadDecision {
            markers: Vec::new(),
            template: Vec::new(),
            report,
        }
    }

    /// Stabilising on an assessed group.
    fn on(a: GroupAssessment, report: HeadReport) -> HeadDecision {
        HeadDecision {
            markers: a.markers,
            template: a.template,
            report,
        }
    }
}

/// Decides the head reference among the kept markers `labels` (`excluded`: the markers left
/// out of training and the share of frames they miss, which named references are checked
/// against). See the module docs.
///
/// # Errors
/// Named markers that do not resolve (or were left out), or fewer than three of them.
pub fn decide(
    choice: &HeadChoice,
    labels: &[String],
    excluded: &[(String, f64)],
    frames: &MarkerFrames<'_>,
) -> Result<HeadDecision> {
    match choice {
        HeadChoice::None => Ok(HeadDecision::none(HeadReport {
            source: "none".into(),
            verdict: "head stabilisation off (--head-reference none)".into(),
            ..HeadReport::default()
        })),
        HeadChoice::Labels {
            patterns,
            requested,
        } => {
            let from = if *requested {
                "--head-reference"
            } else {
                "the regions file's head_reference"
            };
            let markers = resolve_named(patterns, labels, excluded, from)?;
            let mut decision = from_named("named", markers, labels, frames);
            decision.report.requested = *requested;
            Ok(decision)
        }
        HeadChoice::Auto { patterns } => {
            let matched = match_patterns(patterns, labels)?;
            if matched.len() >= 3 {
                return Ok(from_named("name pattern", matched, labels, frames));
            }
            Ok(from_geometry(labels, frames))
        }
    }
}

/// The markers `patterns` name (`from`: who named them, for the errors).
fn resolve_named(
    patterns: &[String],
    labels: &[String],
    excluded: &[(String, f64)],
    from: &str,
) -> Result<Vec<usize>> {
    if let Some((label, share)) = excluded.iter().find(|(l, _)| patterns.contains(l)) {
        bail!(
            "{from} names marker {label:?}, which training left out: it is missing in {:.1} % of the frames",
            100.0 * share
        );
    }
    let regions = Regions {
        regions: [("head_reference".to_string(), patterns.to_vec())].into(),
    };
    let idx = regions
        .resolve(labels)
        .map_err(|e| match e {
            SessionError::UnknownLabel { label, hint, .. } => {
                anyhow!("{from} names marker {label:?}, which the take does not have{hint}")
            }
            SessionError::EmptyRegion { patterns, hint, .. } => {
                anyhow!("{from} matches no marker (patterns {patterns:?}){hint}")
            }
            e => anyhow!("{from}: {e}"),
        })?
        .remove("head_reference")
        .unwrap_or_default();
    if idx.len() < 3 {
        bail!(
            "head stabilisation needs at least 3 reference markers, got {}",
            idx.len()
        );
    }
    Ok(idx)
}

/// Labels matching any of the patterns, case-insensitively.
fn match_patterns(patterns: &[String], labels: &[String]) -> Result<Vec<usize>> {
    let mut set = GlobSetBuilder::new();
    for p in patterns {
        let glob = GlobBuilder::new(p)
            .case_insensitive(true)
            .build()
            .map_err(|e| anyhow!("head pattern {p:?}: {e}"))?;
        set.add(glob);
    }
    let set = set.build().map_err(|e| anyhow!("head patterns: {e}"))?;
    Ok((0..labels.len())
        .filter(|&i| set.is_match(&labels[i]))
        .collect())
}

fn names(markers: &[usize], labels: &[String]) -> Vec<String> {
    markers.iter().map(|&i| labels[i].clone()).collect()
}

fn with_numbers(mut report: HeadReport, a: &GroupAssessment) -> HeadReport {
    report.noise_mm = Some(a.noise_mm);
    report.deformation_mm = Some(a.deformation_mm);
    report.rigid = Some(a.rigid);
    report.motion_mm = Some(a.motion_mm);
    report.pose_error_mm = Some(a.pose_error_mm);
    report.leakage = Some(a.leakage);
    report
}

/// Named markers (by the user or a naming convention): used unless the head's motion is too
/// small for stabilising on them to pay (the verdict says which: a still head, or motion
/// under [`MOTION_FACTOR`] times the pose error they would add).
fn from_named(
    source: &str,
    markers: Vec<usize>,
    labels: &[String],
    frames: &MarkerFrames<'_>,
) -> HeadDecision {
    let report = HeadReport {
        source: source.into(),
        markers: names(&markers, labels),
        ..HeadReport::default()
    };
    let Some(a) = assess_named(frames, &markers) else {
        // Never three of them together: stabilisation would hold one pose forever.
        return HeadDecision::none(HeadReport {
            verdict: "not stabilised: the reference markers are never seen three at a time".into(),
            ..report
        });
    };
    let mut report = with_numbers(report, &a);
    if !a.motion_is_measurable() {
        let why = if a.motion_mm <= MIN_MOTION_MM {
            format!(
                "the head is still (it moves the face by {:.2} mm RMS)",
                a.motion_mm
            )
        } else {
            format!(
                "the head moves the face by {:.2} mm RMS, less than {MOTION_FACTOR} times the {:.2} mm of pose error the reference would add",
                a.motion_mm, a.pose_error_mm
            )
        };
        report.verdict = format!("not stabilised: {why}");
        return HeadDecision::none(report);
    }
    report.stabilised = true;
    report.verdict = format!(
        "stabilised on the {source} markers: head motion {:.2} mm RMS, the reference deforms by {:.2} mm, pose error at the face {:.2} mm",
        a.motion_mm, a.deformation_mm, a.pose_error_mm
    );
    HeadDecision::on(a, report)
}

fn from_geometry(labels: &[String], frames: &MarkerFrames<'_>) -> HeadDecision {
    let search = search_reference(frames, &SearchParams::default());
    let base = HeadReport {
        source: "geometry".into(),
        noise_mm: Some(search.noise_mm),
        ..HeadReport::default()
    };
    match choose(&search.candidates) {
        Choice::Stabilise(a) => stabilised_on_found(base, a, labels),
        Choice::StillHead(a) => {
            let mut report = with_numbers(base, &a);
            report.markers = names(&a.markers, labels);
            report.verdict = format!(
                "not stabilised: no measurable head motion (the most head-like {} {} move the face by {:.2} mm RMS, against {:.2} mm of pose error)",
                if a.rigid { "rigid group" } else { "least-deforming markers" },
                report.markers.join(", "),
                a.motion_mm,
                a.pose_error_mm
            );
            HeadDecision::none(report)
        }
        Choice::MovesWithFace(a) => {
            let mut report = with_numbers(base, &a);
            report.markers = names(&a.markers, labels);
            report.verdict = format!(
                "not stabilised: no head reference (the steadiest markers {} move with the face: their pose explains {:.0} % of the other markers' motion)",
                report.markers.join(", "),
                100.0 * a.leakage
            );
            HeadDecision::none(report)
        }
        Choice::NoCandidate => HeadDecision::none(HeadReport {
            verdict: "not stabilised: fewer than three markers are present often enough".into(),
            ..base
        }),
    }
}

/// Stabilised on the group the search found (rigid, or the least deforming).
fn stabilised_on_found(base: HeadReport, a: GroupAssessment, labels: &[String]) -> HeadDecision {
    let mut report = with_numbers(base, &a);
    report.markers = names(&a.markers, labels);
    report.stabilised = true;
    report.verdict = if a.rigid {
        format!(
            "stabilised on a rigid group found in the capture: head motion {:.2} mm RMS, pose error at the face {:.2} mm",
            a.motion_mm, a.pose_error_mm
        )
    } else {
        format!(
            "no rigid group within the capture's noise ({:.3} mm); stabilised on the least-deforming markers: they deform by {:.2} mm RMS, which costs about {:.2} mm of pose error at the face (head motion {:.2} mm RMS)",
            a.noise_mm, a.deformation_mm, a.pose_error_mm, a.motion_mm
        )
    };
    HeadDecision::on(a, report)
}
