//! The metrics of section 4 as accumulators: a pair or a take goes in, the metric comes out at
//! the end. The whole-slice functions ([`emotion_distance`], [`level_distance`],
//! [`region_distance`]) run the accumulators over every input, so there is one code path and a
//! caller holding one sentence's takes at a time gets the same numbers, up to the order of the
//! floating-point sums when it adds the inputs in another order.

use nalgebra::{DMatrix, DVector};

use super::{EmotionDistance, InterpretError};
use crate::dtw;

fn frames_of(series: &[f64], m: usize) -> Result<usize, InterpretError> {
    if m == 0 || series.len() % m != 0 {
        return Err(InterpretError::BadSeries {
            len: series.len(),
            m,
        });
    }
    Ok(series.len() / m)
}

/// The mean of each component over one take (frames x m series); 0 for an empty take.
///
/// # Errors
/// A series of the wrong shape.
pub fn series_means(series: &[f64], m: usize) -> Result<Vec<f64>, InterpretError> {
    let frames = frames_of(series, m)?;
    let mut sums = vec![0.0; m];
    for row in series.chunks_exact(m) {
        for (acc, v) in sums.iter_mut().zip(row) {
            *acc += v;
        }
    }
    let n = frames.max(1) as f64;
    Ok(sums.into_iter().map(|s| s / n).collect())
}

/// `d_emotion` over pairs added one at a time ([`emotion_distance`] for the metric).
#[derive(Debug, Clone)]
pub struct EmotionDistanceAcc {
    m: usize,
    band: Option<usize>,
    sum: Vec<f64>,
    aligned_samples: Vec<usize>,
}

impl EmotionDistanceAcc {
    /// No pairs yet, `m` components, DTW Sakoe-Chiba radius `band` frames (`None`:
    /// unconstrained). The band is fixed up front: every pair must be aligned alike.
    pub fn new(m: usize, band: Option<usize>) -> Self {
        Self {
            m,
            band,
            sum: vec![0.0; m],
            aligned_samples: Vec::new(),
        }
    }

    /// Aligns one pair and adds its squared differences; returns its aligned samples and the
    /// median of `b − a` over the aligned frames ([`aligned_offset`]).
    ///
    /// # Errors
    /// A series of the wrong shape, or an alignment failure (empty or non-finite series).
    pub fn add_pair(&mut self, a: &[f64], b: &[f64]) -> Result<AlignedPair, InterpretError> {
        let m = self.m;
        let path = align_path(a, b, m, self.band)?;
        for &(i, j) in &path {
            for (k, acc) in self.sum.iter_mut().enumerate() {
                let d = a[i * m + k] - b[j * m + k];
                *acc += d * d;
            }
        }
        self.aligned_samples.push(path.len());
        Ok(AlignedPair {
            samples: path.len(),
            offset: path_offset(a, b, m, &path),
        })
    }

    /// The metric over the pairs added (0 per component without pairs).
    pub fn finish(self) -> EmotionDistance {
        let total: usize = self.aligned_samples.iter().sum();
        let per_component = self
            .sum
            .iter()
            .map(|s| (s / total.max(1) as f64).sqrt())
            .collect();
        EmotionDistance {
            per_component,
            aligned_samples: self.aligned_samples,
        }
    }
}

/// One aligned pair: its aligned samples and the median of `b − a` over them.
#[derive(Debug, Clone, PartialEq)]
pub struct AlignedPair {
    /// Aligned samples (the DTW path's length).
    pub samples: usize,
    /// Median over the path of `b − a`, per component: where the second take sits relative
    /// to the first with what both say matched frame by frame.
    pub offset: Vec<f64>,
}

/// The DTW path of a pair (each series' own mean removed, so a level difference does not pull
/// the alignment).
fn align_path(
    a: &[f64],
    b: &[f64],
    m: usize,
    band: Option<usize>,
) -> Result<Vec<(usize, usize)>, InterpretError> {
    // Shapes checked first, for a typed error naming the series.
    frames_of(a, m)?;
    frames_of(b, m)?;
    Ok(dtw::align(&dtw::demeaned(a, m), &dtw::demeaned(b, m), m, band)?.path)
}

/// The median over the path of `b − a`, per component: robust to the stretches where the
/// two takes do not say the same thing (a take that starts earlier or ends later, a cough),
/// which the forced ends of the path would otherwise average in.
fn path_offset(a: &[f64], b: &[f64], m: usize, path: &[(usize, usize)]) -> Vec<f64> {
    let mut d = vec![0.0; path.len()];
    (0..m)
        .map(|k| {
            for (x, &(i, j)) in d.iter_mut().zip(path) {
                *x = b[j * m + k] - a[i * m + k];
            }
            median(&mut d)
        })
        .collect()
}

/// The median of `values` (reordered), 0 when empty.
fn median(values: &mut [f64]) -> f64 {
    let n = values.len();
    if n == 0 {
        return 0.0;
    }
    values.sort_unstable_by(f64::total_cmp);
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

/// The median of `b − a` over the DTW-aligned frames of two takes of one sentence
/// (Sakoe-Chiba radius `band`): the difference of their levels with the sentence's content
/// matched frame by frame rather than averaged per take.
///
/// # Errors
/// A series of the wrong shape, or an alignment failure (empty or non-finite series).
pub fn aligned_offset(
    a: &[f64],
    b: &[f64],
    m: usize,
    band: Option<usize>,
) -> Result<Vec<f64>, InterpretError> {
    let path = align_path(a, b, m, band)?;
    Ok(path_offset(a, b, m, &path))
}

/// `d_emotion,j` over pairs of component series of the same sentence in two emotions.
///
/// `band` is the DTW Sakoe-Chiba radius in frames (`None`: unconstrained).
///
/// # Errors
/// A series of the wrong shape, or an alignment failure (empty or non-finite series).
pub fn emotion_distance(
    pairs: &[(&[f64], &[f64])],
    m: usize,
    band: Option<usize>,
) -> Result<EmotionDistance, InterpretError> {
    let mut acc = EmotionDistanceAcc::new(m, band);
    for (a, b) in pairs {
        acc.add_pair(a, b)?;
    }
    Ok(acc.finish())
}

/// `d_level` over pairs added one at a time, from the takes' means ([`level_distance`] for
/// the metric): a caller that keeps each take's [`series_means`] need not keep its series.
#[derive(Debug, Clone)]
pub struct LevelDistanceAcc {
    m: usize,
    sum: Vec<f64>,
    pairs: usize,
}

impl LevelDistanceAcc {
    /// No pairs yet, `m` components.
    pub fn new(m: usize) -> Self {
        Self {
            m,
            sum: vec![0.0; m],
            pairs: 0,
        }
    }

    /// Adds one pair given each take's component means ([`series_means`]).
    ///
    /// # Errors
    /// Means of another length than `m` (reported as a series of that length).
    pub fn add_means(&mut self, a: &[f64], b: &[f64]) -> Result<(), InterpretError> {
        if let Some(bad) = [a, b].into_iter().find(|v| v.len() != self.m) {
            return Err(InterpretError::BadSeries {
                len: bad.len(),
                m: self.m,
            });
        }
        for ((acc, ma), mb) in self.sum.iter_mut().zip(a).zip(b) {
            *acc += (ma - mb) * (ma - mb);
        }
        self.pairs += 1;
        Ok(())
    }

    /// Adds one pair of series.
    ///
    /// # Errors
    /// A series of the wrong shape.
    pub fn add_pair(&mut self, a: &[f64], b: &[f64]) -> Result<(), InterpretError> {
        let (ma, mb) = (series_means(a, self.m)?, series_means(b, self.m)?);
        self.add_means(&ma, &mb)
    }

    /// The metric over the pairs added (0 per component without pairs).
    pub fn finish(self) -> Vec<f64> {
        let n = self.pairs.max(1) as f64;
        self.sum.iter().map(|s| (s / n).sqrt()).collect()
    }
}

/// `d_level,j`: the RMS over pairs of the difference of component `j`'s take means.
///
/// Emotion moves a component's level for a whole take, while speech, blinks and noise average
/// out over a take of the same sentence. Unlike `d_emotion`, this does not grow with components
/// that are noise (independent between takes, so their aligned RMS difference is about √2 for a
/// unit-variance component), which makes its peak the robust label of emotion when the variance
/// target keeps many components.
///
/// # Errors
/// A series of the wrong shape.
pub fn level_distance(pairs: &[(&[f64], &[f64])], m: usize) -> Result<Vec<f64>, InterpretError> {
    let mut acc = LevelDistanceAcc::new(m);
    for (a, b) in pairs {
        acc.add_pair(a, b)?;
    }
    Ok(acc.finish())
}

/// The second moments `Σ_t u(t) u(t)ᵀ` of the components over every frame added, and the
/// frame count: all the region metric needs, for any region and any emotion set (`‖M_R w‖²`
/// summed over frames is `Σ_ab G_ab Σ_t w_a w_b`). Holding them instead of the series lets a
/// session stream past before its emotion set is known, in one read.
#[derive(Debug, Clone)]
pub struct ComponentMoments {
    m: usize,
    /// Upper triangle (`a ≤ b`) of the moments, row-major m x m.
    sum: Vec<f64>,
    frames: usize,
}

impl ComponentMoments {
    /// No frames yet, `m` components.
    pub fn new(m: usize) -> Self {
        Self {
            m,
            sum: vec![0.0; m * m],
            frames: 0,
        }
    }

    /// Adds every frame of one take (frames x m series).
    ///
    /// # Errors
    /// A series of the wrong shape.
    pub fn add_series(&mut self, series: &[f64]) -> Result<(), InterpretError> {
        let m = self.m;
        self.frames += frames_of(series, m)?;
        for row in series.chunks_exact(m) {
            for (a, &ua) in row.iter().enumerate() {
                let line = &mut self.sum[a * m + a..(a + 1) * m];
                for (acc, &ub) in line.iter_mut().zip(&row[a..]) {
                    *acc += ua * ub;
                }
            }
        }
        Ok(())
    }

    fn moment(&self, a: usize, b: usize) -> f64 {
        let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
        self.sum[lo * self.m + hi]
    }

    /// `d_region,i` for every component `i` (Eq. 4) over the frames added; see
    /// [`region_distance`].
    ///
    /// # Errors
    /// An empty region, a marker outside the model, or a model of another component count.
    pub fn region_distance(
        &self,
        mixing: &DMatrix<f64>,
        region: &[usize],
        emotion: &[usize],
    ) -> Result<Vec<f64>, InterpretError> {
        let m = self.m;
        if mixing.ncols() != m {
            return Err(InterpretError::ComponentCountMismatch {
                expected: m,
                got: mixing.ncols(),
            });
        }
        let gram = region_gram(mixing, region)?;
        let kept: Vec<usize> = (0..m).filter(|i| !emotion.contains(i)).collect();
        // Σ_t ||v_t||², v_t = M_R (u_t with E zeroed).
        let mut base = 0.0;
        // Σ_t u_i(t) (G w_t)_i, and Σ_t u_i(t)².
        let mut cross = DVector::<f64>::zeros(m);
        for &a in &kept {
            for &b in &kept {
                let term = gram[(a, b)] * self.moment(a, b);
                base += term;
                cross[a] += term;
            }
        }
        let norm = (self.frames.max(1) * region.len()) as f64;
        let d_e = (base / norm).max(0.0).sqrt();
        Ok((0..m)
            .map(|i| {
                if emotion.contains(&i) {
                    return 0.0;
                }
                let with_i = base - 2.0 * cross[i] + gram[(i, i)] * self.moment(i, i);
                (with_i / norm).max(0.0).sqrt() - d_e
            })
            .collect())
    }
}

/// Gram matrix of a region's rows of the mixing matrix: `||M_R w||² = wᵀ G w`.
fn region_gram(mixing: &DMatrix<f64>, region: &[usize]) -> Result<DMatrix<f64>, InterpretError> {
    let markers = mixing.nrows() / 3;
    if region.is_empty() {
        return Err(InterpretError::EmptyRegion);
    }
    if let Some(&marker) = region.iter().find(|&&r| r >= markers) {
        return Err(InterpretError::BadMarker { marker, markers });
    }
    let m = mixing.ncols();
    let mut gram = DMatrix::<f64>::zeros(m, m);
    for &r in region {
        for row in r * 3..r * 3 + 3 {
            let line = mixing.row(row);
            gram += line.transpose() * line;
        }
    }
    Ok(gram)
}

/// `d_region,i` for every component `i` (Eq. 4), given the emotion subset `emotion` (`E`, may be
/// empty) and the region's marker indices.
///
/// The distance of Eq. 3 averages the squared 3-D marker distance over the region's `r` markers
/// and all frames of all takes, then takes the square root.
///
/// # Errors
/// Bad series shape, an empty region or a marker outside the model.
pub fn region_distance(
    mixing: &DMatrix<f64>,
    takes: &[&[f64]],
    region: &[usize],
    emotion: &[usize],
) -> Result<Vec<f64>, InterpretError> {
    // The region first, as its errors name the caller's mistake rather than the data's.
    region_gram(mixing, region)?;
    let mut moments = ComponentMoments::new(mixing.ncols());
    for series in takes {
        moments.add_series(series)?;
    }
    moments.region_distance(mixing, region, emotion)
}
