//! `emoshift regions`: a first `regions.toml` proposed from a take's marker names and geometry
//! (issue 37), so `analyze` can run on a layout nobody wrote a regions file for. Names are read
//! without an asset prefix (Motive's `Face:`), and written in full, so the file matches the
//! take. Every marker line carries a comment saying why it is there: a proposal to check, not a
//! verdict.

use std::fmt::Write as _;

use replay::Take;

use crate::offline::training::DEFAULT_MAX_MISSING;

/// Name fragments (lower case, asset prefix removed) that put a marker in a region, in the
/// order regions are tried: a brow is never an eyelid, whatever else its name says.
const BY_NAME: [(&str, &[&str]); 3] = [
    ("eyebrows", &["brow"]),
    ("eyelids", &["lid", "blink", "eye"]),
    ("mouth", &["lip", "mouth", "jaw", "chin", "mth"]),
];

/// Head-reference names, matched only at the start of a word ([`starts_a_word`]): a
/// `NoseHead` sits on the nose, not the skull (AnimFace's layout), while `HeadTop`, `LTemple`,
/// `R_Ear`, `ForeHead_M` and Plug-in Gait's `LFHD` name head markers. `train`'s own name
/// patterns (`head*`, `hat*`, `helmet*`) are among them.
const HEAD_BY_NAME: [&str; 9] = [
    "head", "forehead", "temple", "ear", "hat", "helmet", "hdr", "fhd", "bhd",
];

/// Whether `key` starts one of `name`'s words (split at `_`, `-`, `.` and spaces), after an
/// optional side prefix (`l`, `r`, `left`, `right`).
fn starts_a_word(name: &str, key: &str) -> bool {
    name.split(['_', '-', '.', ' ']).any(|word| {
        ["", "left", "right", "l", "r"].iter().any(|side| {
            word.strip_prefix(side)
                .is_some_and(|rest| rest.starts_with(key))
        })
    })
}

/// The region `name` (lower case, asset prefix removed) proposes, and the fragment that did.
fn region_by_name(name: &str) -> Option<(&'static str, &'static str)> {
    BY_NAME
        .iter()
        .find_map(|(region, keys)| {
            let key = keys.iter().find(|k| name.contains(*k))?;
            Some((*region, *key))
        })
        .or_else(|| {
            let key = HEAD_BY_NAME.iter().find(|k| starts_a_word(name, k))?;
            Some(("head_reference", *key))
        })
}

/// Markers the geometry gives a region when no name does: shares of the face's height.
const MOUTH_BELOW: f64 = 0.35;
const BROWS_ABOVE: f64 = 0.75;
const LIDS_FROM: f64 = 0.55;
/// Markers taken as the head reference from the geometry: the ones that move least.
const HEAD_MARKERS: usize = 4;

/// One marker proposed for a region, with why.
#[derive(Debug, Clone, PartialEq)]
pub struct Proposal {
    /// The region: mouth, eyebrows, eyelids or head_reference.
    pub region: &'static str,
    /// The marker's label, as the take names it.
    pub label: String,
    /// Why.
    pub why: String,
}

/// A marker's name without its asset prefix (`Face:BrowL` -> `BrowL`).
fn bare(label: &str) -> &str {
    label.rsplit_once(':').map_or(label, |(_, m)| m)
}

/// What `regions` proposes for a take.
#[derive(Debug, Clone, PartialEq)]
pub struct Proposed {
    /// The markers proposed, region by region.
    pub markers: Vec<Proposal>,
    /// Markers left out with the share of frames they are missing in: `train` leaves them out
    /// of the model (above [`DEFAULT_MAX_MISSING`]), so `analyze` could not find them.
    pub left_out: Vec<(String, f64)>,
    /// Forehead markers not proposed as the head reference because others name the skull
    /// (see [`propose`]).
    pub forehead_not_head: Vec<String>,
}

/// The head-name fragment of forehead skin, which moves with the brows: a head reference only
/// where no marker names the skull.
const FOREHEAD: &str = "forehead";

/// The proposals for `take`: by name first; a region no name fills, from the geometry. A
/// marker missing in more of the take's frames than `train` keeps is proposed for no region.
/// Forehead markers are proposed as the head reference only when no marker names the skull (a
/// head band, the temples, the ears, Plug-in Gait's FHD/BHD): forehead skin lifts with the
/// brows, a skull marker does not.
pub fn propose(take: &Take) -> Proposed {
    let frames = take.n_frames().max(1) as f64;
    let share: Vec<f64> = take
        .missing_per_marker()
        .iter()
        .map(|&gone| gone as f64 / frames)
        .collect();
    let kept = |i: usize| share[i] <= DEFAULT_MAX_MISSING;
    let left_out = (0..take.n_markers())
        .filter(|&i| !kept(i))
        .map(|i| (take.labels[i].clone(), share[i]))
        .collect();
    let mut named: Vec<(Proposal, &str)> = Vec::new();
    for (i, label) in take.labels.iter().enumerate().filter(|(i, _)| kept(*i)) {
        let name = bare(label).to_lowercase();
        if let Some((region, key)) = region_by_name(&name) {
            let why = format!("name contains {key:?}");
            let label = take.labels[i].clone();
            named.push((Proposal { region, label, why }, key));
        }
    }
    let is_forehead =
        |(p, key): &(Proposal, &str)| p.region == "head_reference" && *key == FOREHEAD;
    let skull = named
        .iter()
        .any(|n| n.0.region == "head_reference" && !is_forehead(n));
    let (forehead, named): (Vec<_>, Vec<_>) =
        named.into_iter().partition(|n| skull && is_forehead(n));
    let forehead_not_head = forehead.into_iter().map(|(p, _)| p.label).collect();
    let mut out: Vec<Proposal> = named.into_iter().map(|(p, _)| p).collect();
    let mut stats = marker_stats(take);
    for (i, s) in stats.iter_mut().enumerate() {
        if !kept(i) {
            *s = None;
        }
    }
    for region in ["mouth", "eyebrows", "eyelids", "head_reference"] {
        if !out.iter().any(|p| p.region == region) {
            let taken: Vec<String> = out.iter().map(|p| p.label.clone()).collect();
            out.extend(by_geometry(take, &stats, region, &taken));
        }
    }
    Proposed {
        markers: out,
        left_out,
        forehead_not_head,
    }
}

/// Per marker: mean position and RMS motion about it (mm), over the frames where it is seen.
fn marker_stats(take: &Take) -> Vec<Option<([f64; 3], f64)>> {
    (0..take.n_markers())
        .map(|m| {
            let seen: Vec<[f32; 3]> = (0..take.n_frames())
                .filter_map(|f| take.sample(f, m))
                .collect();
            if seen.is_empty() {
                return None;
            }
            let n = seen.len() as f64;
            let mean: [f64; 3] =
                std::array::from_fn(|a| seen.iter().map(|p| f64::from(p[a])).sum::<f64>() / n);
            let var = seen
                .iter()
                .map(|p| {
                    (0..3)
                        .map(|a| (f64::from(p[a]) - mean[a]).powi(2))
                        .sum::<f64>()
                })
                .sum::<f64>()
                / n;
            Some((mean, var.sqrt()))
        })
        .collect()
}

/// A region from the geometry: height bands along the axis the markers span most (the face
/// is taller than wide or deep), or the least-moving markers for the head reference.
fn by_geometry(
    take: &Take,
    stats: &[Option<([f64; 3], f64)>],
    region: &'static str,
    taken: &[String],
) -> Vec<Proposal> {
    let seen: Vec<(usize, [f64; 3], f64)> = stats
        .iter()
        .enumerate()
        .filter_map(|(i, s)| s.map(|(mean, motion)| (i, mean, motion)))
        .collect();
    let span = |a: usize| {
        let lo = seen.iter().map(|s| s.1[a]).fold(f64::INFINITY, f64::min);
        let hi = seen
            .iter()
            .map(|s| s.1[a])
            .fold(f64::NEG_INFINITY, f64::max);
        (lo, (hi - lo).max(1e-9))
    };
    let up = (0..3)
        .max_by(|&a, &b| span(a).1.total_cmp(&span(b).1))
        .unwrap_or(1);
    let (lo, height) = span(up);
    let axis = ["x", "y", "z"][up];
    let mut picked: Vec<(usize, String)> = Vec::new();
    if region == "head_reference" {
        // Not a marker another region holds: the face's own markers make a poor reference.
        let mut still: Vec<_> = seen
            .iter()
            .filter(|s| !taken.contains(&take.labels[s.0]))
            .copied()
            .collect();
        still.sort_by(|a, b| a.2.total_cmp(&b.2));
        for (i, _, motion) in still.into_iter().take(HEAD_MARKERS) {
            picked.push((i, format!("moves least over the take ({motion:.2} mm RMS)")));
        }
    } else {
        for (i, mean, _) in &seen {
            let h = (mean[up] - lo) / height;
            let band = match region {
                "mouth" => h < MOUTH_BELOW,
                "eyebrows" => h > BROWS_ABOVE,
                _ => (LIDS_FROM..=BROWS_ABOVE).contains(&h),
            };
            if band {
                picked.push((
                    *i,
                    format!("at {:.0} % of the face's height ({axis} up)", 100.0 * h),
                ));
            }
        }
    }
    picked
        .into_iter()
        .map(|(i, why)| Proposal {
            region,
            label: take.labels[i].clone(),
            why: format!("geometry: {why}"),
        })
        .collect()
}

/// Why a marker of `left_out` is there, for the file and the terminal alike.
pub fn why_left_out(share: f64) -> String {
    format!(
        "missing in {:.1} % of the frames (train leaves out markers missing in over {:.0} %)",
        100.0 * share,
        100.0 * DEFAULT_MAX_MISSING
    )
}

/// The proposals as `regions.toml`, one marker a line with its reason, and the markers left
/// out in a comment.
pub fn to_toml(proposed: &Proposed, source: &str) -> String {
    let proposals = &proposed.markers;
    let mut out = format!(
        "# regions.toml proposed by `emoshift regions` from {source}: check every line before\n\
         # `emoshift analyze` (which needs mouth, eyebrows and eyelids); head_reference names\n\
         # markers that move with the head only, for `train`.\n"
    );
    for (label, share) in &proposed.left_out {
        let _ = writeln!(out, "# left out: {label:?}, {}", why_left_out(*share));
    }
    for region in ["mouth", "eyebrows", "eyelids", "head_reference"] {
        if !proposals.iter().any(|p| p.region == region) {
            let _ = writeln!(out, "# {region}: no marker found; name its markers here");
            continue;
        }
        let _ = writeln!(out, "{region} = [");
        for p in proposals.iter().filter(|p| p.region == region) {
            let _ = writeln!(out, "    {:?},  # {}", p.label, p.why);
        }
        let _ = writeln!(out, "]");
    }
    if !proposed.forehead_not_head.is_empty() {
        let _ = writeln!(
            out,
            "# not proposed as the head reference: {} (forehead skin lifts with the brows; the \
             markers above name the skull). Add them if they are on a band or a cap.",
            (proposed.forehead_not_head.iter())
                .map(|l| format!("{l:?}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn of<'a>(p: &'a Proposed, region: &str) -> Vec<&'a str> {
        p.markers
            .iter()
            .filter(|x| x.region == region)
            .map(|x| x.label.as_str())
            .collect()
    }

    #[test]
    fn names_with_motives_prefix_and_numbered_layouts_both_get_regions() {
        let labels = [
            "Face:BrowL",
            "Face:UpperLip",
            "Face:LidR",
            "Face:HeadTop",
            "Face:Cheek",
        ];
        let mut take = Take::new(labels.iter().map(|s| s.to_string()).collect(), 100.0, 1);
        take.push_frame(&[0.0; 15], &[false; 5]);
        let p = propose(&take);
        assert_eq!(of(&p, "eyebrows"), ["Face:BrowL"]);
        assert_eq!(of(&p, "mouth"), ["Face:UpperLip"]);
        assert_eq!(of(&p, "eyelids"), ["Face:LidR"]);
        assert_eq!(of(&p, "head_reference"), ["Face:HeadTop"]);
        let text = to_toml(&p, "t.c3d");
        let back = replay::session::Regions::parse(&text).expect("valid regions.toml");
        assert!(back
            .resolve(&take.labels)
            .expect("resolves")
            .contains_key("mouth"));
        assert!(
            text.contains("\"Face:BrowL\",  # name contains \"brow\""),
            "{text}"
        );

        // Numbered markers, the face 200 mm tall along y: bands by height.
        let mut take = Take::new((0..5).map(|i| format!("M{i}")).collect(), 100.0, 1);
        let heights = [10.0, 90.0, 130.0, 190.0, 200.0];
        let xyz: Vec<f32> = heights.iter().flat_map(|&h| [0.0, h, 0.0]).collect();
        take.push_frame(&xyz, &[false; 5]);
        let p = propose(&take);
        assert_eq!(of(&p, "mouth"), ["M0"]);
        assert_eq!(of(&p, "eyelids"), ["M2"]);
        assert_eq!(of(&p, "eyebrows"), ["M3", "M4"]);
        assert!(p.left_out.is_empty());
    }

    /// AnimFace names three markers on the nose `NoseHead*` and three on the forehead
    /// `ForeHead_*`: only the forehead is proposed as the head reference.
    #[test]
    fn head_names_count_only_at_the_start_of_a_word() {
        let heads = [
            "ForeHead_M",
            "LTemple",
            "R_Ear",
            "HeadTop",
            "LFHD",
            "Left-Ear",
            "hat",
        ];
        let others = [
            "NoseHead",
            "NoseHead_L",
            "Nosehead_R",
            "Cheek_Near",
            "Chat",
            "Thead",
        ];
        for name in heads {
            let region = region_by_name(&name.to_lowercase()).map(|(r, _)| r);
            assert_eq!(region, Some("head_reference"), "{name}");
        }
        for name in others {
            assert_eq!(region_by_name(&name.to_lowercase()), None, "{name}");
        }
    }

    /// The generator's Vicon layout names Plug-in Gait's head markers and twelve forehead
    /// markers: the skull markers are the head reference, the forehead ones are named in a
    /// comment. Forehead markers alone (AnimFace) are still the head reference.
    #[test]
    fn forehead_markers_are_the_head_reference_only_without_skull_markers() {
        let labels = ["LFHD", "RFHD", "Forehead1", "Forehead2", "BrowL"];
        let mut take = Take::new(labels.iter().map(|s| s.to_string()).collect(), 100.0, 1);
        take.push_frame(&[0.0; 15], &[false; 5]);
        let p = propose(&take);
        assert_eq!(of(&p, "head_reference"), ["LFHD", "RFHD"]);
        assert_eq!(p.forehead_not_head, ["Forehead1", "Forehead2"]);
        let text = to_toml(&p, "t.c3d");
        assert!(
            text.contains("# not proposed as the head reference: \"Forehead1\", \"Forehead2\" ("),
            "{text}"
        );

        let labels = ["ForeHead_M", "ForeHead_L", "NoseHead", "BrowL"];
        let mut take = Take::new(labels.iter().map(|s| s.to_string()).collect(), 100.0, 1);
        take.push_frame(&[0.0; 12], &[false; 4]);
        let p = propose(&take);
        assert_eq!(of(&p, "head_reference"), ["ForeHead_M", "ForeHead_L"]);
        assert!(p.forehead_not_head.is_empty());
        assert!(!to_toml(&p, "t.c3d").contains("not proposed"));
    }

    /// Facial-Sing's `Unlabeled1` is missing in 99 % of its frames: `train` leaves it out, so a
    /// region naming it would stop `analyze`. Neither its name nor its place may propose it.
    #[test]
    fn a_marker_missing_in_most_frames_is_proposed_for_no_region() {
        let labels = ["BrowL", "BrowR", "M2", "M3", "M4"];
        let mut take = Take::new(labels.iter().map(|s| s.to_string()).collect(), 100.0, 1);
        let heights = [190.0, 190.0, 10.0, 130.0, 200.0];
        let xyz: Vec<f32> = heights.iter().flat_map(|&h| [0.0, h, 0.0]).collect();
        for f in 0..4 {
            // BrowR is missing in 2 of 4 frames (kept, as train keeps it); M4 in 3 of 4.
            take.push_frame(&xyz, &[false, f < 2, false, false, f < 3]);
        }
        let p = propose(&take);
        assert_eq!(of(&p, "eyebrows"), ["BrowL", "BrowR"]);
        assert_eq!(p.left_out, [("M4".to_string(), 0.75)]);
        assert!(!p.markers.iter().any(|x| x.label == "M4"), "{p:?}");
        let text = to_toml(&p, "t.c3d");
        assert!(
            text.contains("# left out: \"M4\", missing in 75.0 % of the frames"),
            "{text}"
        );

        // With no brow name, the top band comes from the geometry, without M4 in it.
        let mut take = Take::new((0..5).map(|i| format!("M{i}")).collect(), 100.0, 1);
        for f in 0..4 {
            take.push_frame(&xyz, &[false, false, false, false, f < 3]);
        }
        assert_eq!(of(&propose(&take), "eyebrows"), ["M0", "M1"]);
    }
}
