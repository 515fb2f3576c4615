//! The emotion space: each emotion is a point (a level vector) in `k` emotion directions.
//!
//! Known names get fixed, well-separated points; a name may also be given an explicit point
//! ([`EmotionPoint`], `sad=-0.6,-0.8`); any other name gets the next spare point at least
//! [`SPARE_SEPARATION`] from every point already handed out.
//!
//! | emotion    | k = 1 | k = 2        | k = 3              |
//! |------------|-------|--------------|--------------------|
//! | neutral    | 0     | (0, 0)       | (0, 0, 0)          |
//! | happy      | 1     | (1, 0)       | (1, 0, 0)          |
//! | frustrated | -1    | (-1, 0.3)    | (-1, 0.3, 0)       |
//! | angry      | spare | (-0.2, 1)    | (-0.2, 1, 0)       |
//! | sad        | spare | (-0.6, -0.8) | (-0.3, -0.2, 1)    |
//! | surprised  | spare | spare        | (0.2, -1, 0)       |
//! | fear       | spare | spare        | (-0.3, 0.6, 0.9)   |
//!
//! Axis 0 is the smile (+) / frown (-) field, axis 1 brow knit + lip press (anger), axis 2 inner
//! brow raise + mouth corners down (sadness); see [`expressions`](super::expressions). With two
//! axes sadness lies where the knit is undone (inner brows up and apart) and the mouth frowns;
//! with three it has its own axis and the undone knit is left to surprise.

use std::str::FromStr;

use super::SynthError;

/// Fixed levels of the well-known emotions on a single emotion direction.
const KNOWN_LEVELS: [(&str, f64); 3] = [("neutral", 0.0), ("happy", 1.0), ("frustrated", -1.0)];
/// Levels handed out, in order, to other names on a single direction (then ±3, ±3.5, ...).
const SPARE_LEVELS: [f64; 8] = [0.5, -0.5, 1.5, -1.5, 2.0, -2.0, 2.5, -2.5];
/// Fixed points of the well-known emotions in two directions.
const KNOWN_POINTS_2: [(&str, [f64; 2]); 5] = [
    ("neutral", [0.0, 0.0]),
    ("happy", [1.0, 0.0]),
    ("frustrated", [-1.0, 0.3]),
    ("angry", [-0.2, 1.0]),
    ("sad", [-0.6, -0.8]),
];
/// Fixed points of the well-known emotions in three directions.
const KNOWN_POINTS_3: [(&str, [f64; 3]); 7] = [
    ("neutral", [0.0, 0.0, 0.0]),
    ("happy", [1.0, 0.0, 0.0]),
    ("frustrated", [-1.0, 0.3, 0.0]),
    ("angry", [-0.2, 1.0, 0.0]),
    ("sad", [-0.3, -0.2, 1.0]),
    ("surprised", [0.2, -1.0, 0.0]),
    ("fear", [-0.3, 0.6, 0.9]),
];
/// Smallest distance between a spare point and any other point of the session.
pub const SPARE_SEPARATION: f64 = 0.5;
/// Spacing of the lattice spare points are taken from.
const SPARE_STEP: f64 = 0.5;

/// An explicit point for one emotion, written `name=x[,y[,z]]` (one coordinate per emotion
/// direction), e.g. `sad=-0.6,-0.8`.
#[derive(Debug, Clone, PartialEq)]
pub struct EmotionPoint {
    /// Emotion name.
    pub name: String,
    /// Its level on each emotion direction.
    pub point: Vec<f64>,
}

impl FromStr for EmotionPoint {
    type Err = SynthError;

    /// Parses `name=x[,y[,z]]`.
    fn from_str(text: &str) -> Result<EmotionPoint, SynthError> {
        let bad = || SynthError::PointSyntax {
            text: text.to_string(),
        };
        let (name, coords) = text.split_once('=').ok_or_else(bad)?;
        let point = coords
            .split(',')
            .map(|c| c.trim().parse::<f64>().ok().filter(|v| v.is_finite()))
            .collect::<Option<Vec<f64>>>()
            .ok_or_else(bad)?;
        Ok(EmotionPoint {
            name: name.trim().to_string(),
            point,
        })
    }
}

/// The fixed point of a well-known emotion in `dims` directions, if it has one.
pub fn known_point(name: &str, dims: usize) -> Option<Vec<f64>> {
    match dims {
        1 => KNOWN_LEVELS
            .iter()
            .find(|(k, _)| *k == name)
            .map(|(_, l)| vec![*l]),
        2 => KNOWN_POINTS_2
            .iter()
            .find(|(k, _)| *k == name)
            .map(|(_, p)| p.to_vec()),
        3 => KNOWN_POINTS_3
            .iter()
            .find(|(k, _)| *k == name)
            .map(|(_, p)| p.to_vec()),
        _ => None,
    }
}

/// The point of each emotion, in list order: an explicit point if given, else the known point,
/// else the next spare point at least [`SPARE_SEPARATION`] from every point already used (the
/// explicit and known ones of the whole list included). With one direction and no explicit
/// points these are the generator's historic levels: neutral 0, happy 1, frustrated -1, then
/// 0.5, -0.5, 1.5, -1.5, ... for other names.
pub fn emotion_points(names: &[String], dims: usize, explicit: &[EmotionPoint]) -> Vec<Vec<f64>> {
    let fixed = |n: &str| {
        explicit
            .iter()
            .find(|p| p.name == n)
            .map(|p| p.point.clone())
            .or_else(|| known_point(n, dims))
    };
    let mut used: Vec<Vec<f64>> = names.iter().filter_map(|n| fixed(n)).collect();
    let mut spare = spare_candidates(dims);
    names
        .iter()
        .map(|n| {
            fixed(n).unwrap_or_else(|| {
                let p = spare
                    .by_ref()
                    .find(|c| {
                        used.iter()
                            .all(|u| distance(u, c) >= SPARE_SEPARATION - 1e-9)
                    })
                    .expect("the spare candidates are unbounded, the used points finite");
                used.push(p.clone());
                p
            })
        })
        .collect()
}

/// Euclidean distance between two points of the same space.
pub fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// Spare candidates, in order: on one direction the historic levels, then ±3, ±3.5, ...; in
/// more, the points of a lattice of spacing 0.5, shell by shell outwards from neutral (the
/// origin itself left out), nearest first within a shell.
fn spare_candidates(dims: usize) -> Box<dyn Iterator<Item = Vec<f64>>> {
    if dims == 1 {
        let tail = (6..).flat_map(|k| [f64::from(k) * 0.5, -f64::from(k) * 0.5]);
        return Box::new(SPARE_LEVELS.iter().copied().chain(tail).map(|l| vec![l]));
    }
    Box::new((1i32..).flat_map(move |r| lattice_shell(dims, r)))
}

/// The integer vectors of `dims` coordinates whose largest |coordinate| is `r`, scaled by
/// [`SPARE_STEP`], ordered by length, then with larger coordinates first.
fn lattice_shell(dims: usize, r: i32) -> Vec<Vec<f64>> {
    let mut shell: Vec<Vec<i32>> = vec![vec![]];
    for _ in 0..dims {
        shell = shell
            .into_iter()
            .flat_map(|v| {
                (-r..=r).rev().map(move |c| {
                    let mut w = v.clone();
                    w.push(c);
                    w
                })
            })
            .collect();
    }
    shell.retain(|v| v.iter().any(|c| c.abs() == r));
    shell.sort_by_key(|v| v.iter().map(|c| c * c).sum::<i32>());
    shell
        .into_iter()
        .map(|v| v.iter().map(|&c| f64::from(c) * SPARE_STEP).collect())
        .collect()
}

/// `Σ weight · point` over `(point, weight)` pairs: the level vector of a blend such as
/// `sad:0.5, angry:0.5`. `None` when the points do not all have `dims` coordinates.
pub fn blend<'a>(
    dims: usize,
    parts: impl IntoIterator<Item = (&'a [f64], f64)>,
) -> Option<Vec<f64>> {
    let mut out = vec![0.0; dims];
    for (point, weight) in parts {
        if point.len() != dims {
            return None;
        }
        for (o, p) in out.iter_mut().zip(point) {
            *o += weight * p;
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests;
