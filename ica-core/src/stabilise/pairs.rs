//! The strain of marker pairs: how much a pair's distance varies beyond noise, relative to its
//! length (see [`super::search`], step 3).
//!
//! A face of 109 markers has 5,886 pairs, and 60 to 75 % of them are within three times the
//! rigid limit on every face tried (synthetic, Facial-Sing, AnimFace): no cheap screen leaves
//! few to measure. So every pair is measured, on a bounded thin sample of [`PAIR_SAMPLES`]
//! triples (a median and two MADs of a few hundred values: the MAD's own error is about 7 %
//! there), in f32, its selections on integer keys of the floats, rows at once on the current
//! rayon pool: a few microseconds a pair.

use rayon::prelude::*;

use super::sample::Sample;

/// Triples (evenly over the sample) a pair's strain is measured on.
pub const PAIR_SAMPLES: usize = 256;

/// Strain of every candidate pair (∞ where too few samples overlap).
pub(super) struct PairTable {
    markers: Vec<usize>,
    strain: Vec<f64>,
}

impl PairTable {
    /// The strains of every pair of `markers`.
    pub(super) fn measure(sample: &Sample, markers: &[usize]) -> Self {
        let k = markers.len();
        let thin = ThinColumns::new(sample, markers, PAIR_SAMPLES);
        let rows: Vec<Vec<f64>> = (0..k)
            .into_par_iter()
            .map_init(Scratch::default, |scratch, i| {
                (i + 1..k).map(|j| thin.strain(i, j, scratch)).collect()
            })
            .collect();
        let mut strain = vec![f64::INFINITY; k * k];
        for (i, row) in rows.iter().enumerate() {
            for (j, &s) in (i + 1..k).zip(row) {
                strain[i * k + j] = s;
                strain[j * k + i] = s;
            }
        }
        PairTable {
            markers: markers.to_vec(),
            strain,
        }
    }

    pub(super) fn len(&self) -> usize {
        self.markers.len()
    }

    pub(super) fn strain(&self, i: usize, j: usize) -> f64 {
        self.strain[i * self.len() + j]
    }

    /// Pairs (i < j) by increasing strain.
    pub(super) fn sorted_pairs(&self) -> Vec<(usize, usize)> {
        let k = self.len();
        let mut pairs: Vec<(usize, usize)> = (0..k)
            .flat_map(|i| (i + 1..k).map(move |j| (i, j)))
            .filter(|&(i, j)| self.strain(i, j).is_finite())
            .collect();
        pairs.sort_by(|a, b| self.strain(a.0, a.1).total_cmp(&self.strain(b.0, b.1)));
        pairs
    }

    pub(super) fn mean_strain(&self, c: usize, group: &[usize]) -> f64 {
        group.iter().map(|&g| self.strain(c, g)).sum::<f64>() / group.len() as f64
    }

    pub(super) fn to_markers(&self, group: &[usize]) -> Vec<usize> {
        let mut out: Vec<usize> = group.iter().map(|&g| self.markers[g]).collect();
        out.sort_unstable();
        out
    }
}

/// Reused buffers of one measurement.
#[derive(Default)]
struct Scratch {
    dist: Vec<f32>,
    d: Vec<u32>,
    d2: Vec<u32>,
}

/// Distances between two markers over the stored frames of their columns (NaN where either is
/// absent).
fn distances(ax: [&[f32]; 3], bx: [&[f32]; 3], out: &mut Vec<f32>) {
    let t = ax[0].len();
    out.clear();
    out.resize(t, 0.0);
    for (a, b) in ax.iter().zip(bx) {
        for ((o, &p), &q) in out.iter_mut().zip(*a).zip(b) {
            *o += (p - q) * (p - q);
        }
    }
    for o in out.iter_mut() {
        *o = o.sqrt();
    }
}

/// The robust spread (MAD) of a pair's distance beyond the robust spread of its second
/// differences / √6 (the noise), relative to its median length, from the distances in
/// `s.dist` (three per sampled triple); ∞ with fewer than 10 of either. In f32: distances of
/// tens of mm keep their second differences to 1e-5 mm. Selected on integer keys of the floats
/// ([`order_key`]): their order at a fraction of a float comparison's cost.
fn strain_of(s: &mut Scratch) -> f64 {
    s.d.clear();
    s.d2.clear();
    for t in s.dist.chunks_exact(3) {
        let (before, at, after) = (t[0], t[1], t[2]);
        if at.is_finite() {
            s.d.push(order_key(at));
            let d2 = before - 2.0 * at + after;
            if d2.is_finite() {
                s.d2.push(order_key(d2));
            }
        }
    }
    if s.d.len() < 10 || s.d2.len() < 10 {
        return f64::INFINITY;
    }
    let (length, spread) = median_and_mad(&mut s.d);
    let (_, noise) = median_and_mad(&mut s.d2);
    let (length, spread, noise) = (
        f64::from(length),
        f64::from(spread),
        f64::from(noise) / 6f64.sqrt(),
    );
    let excess = (spread * spread - noise * noise).max(0.0).sqrt();
    excess / length.max(1e-6)
}

/// A key whose integer order is the order of the (finite) floats: the bits with the sign bit
/// set for positive values, all bits flipped for negative ones.
fn order_key(v: f32) -> u32 {
    let bits = v.to_bits();
    if bits >> 31 == 1 {
        !bits
    } else {
        bits | 1 << 31
    }
}

fn from_key(k: u32) -> f32 {
    f32::from_bits(if k >> 31 == 1 { k & !(1 << 31) } else { !k })
}

/// The median and `1.4826 · MAD` of keyed values, at the nearest rank as
/// [`crate::robust::mad`] takes them (`keys` is reordered and overwritten).
fn median_and_mad(keys: &mut [u32]) -> (f32, f32) {
    let rank = ((keys.len() - 1) as f64 * 0.5).round() as usize;
    let median = from_key(*keys.select_nth_unstable(rank).1);
    for k in keys.iter_mut() {
        *k = order_key((from_key(*k) - median).abs());
    }
    let mad = from_key(*keys.select_nth_unstable(rank).1);
    (median, 1.4826 * mad)
}

/// The candidate markers' columns over a thin sample of triples.
struct ThinColumns {
    /// Marker-major: candidate i's axis a is `values[(i * 3 + a) * t..][..t]`.
    values: Vec<f32>,
    t: usize,
}

impl ThinColumns {
    fn new(sample: &Sample, markers: &[usize], triples: usize) -> Self {
        let every = sample.frames().div_ceil(triples.max(1)).max(1);
        let chosen: Vec<usize> = (0..sample.frames()).step_by(every).collect();
        let t = 3 * chosen.len();
        let mut values = Vec::with_capacity(markers.len() * 3 * t);
        for &m in markers {
            for axis in 0..3 {
                let column = sample.column(m, axis);
                values.extend(chosen.iter().flat_map(|&s| &column[3 * s..3 * s + 3]));
            }
        }
        ThinColumns { values, t }
    }

    fn axes(&self, i: usize) -> [&[f32]; 3] {
        [0, 1, 2].map(|a| &self.values[(i * 3 + a) * self.t..(i * 3 + a + 1) * self.t])
    }

    /// The strain of candidates `i` and `j` over these triples.
    fn strain(&self, i: usize, j: usize, s: &mut Scratch) -> f64 {
        distances(self.axes(i), self.axes(j), &mut s.dist);
        strain_of(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_order_floats_and_come_back() {
        let values = [-1e9f32, -3.5, -0.0, 0.0, 1e-30, 2.25, 7e12];
        let keys: Vec<u32> = values.iter().map(|&v| order_key(v)).collect();
        assert!(keys.windows(2).all(|w| w[0] <= w[1]), "{keys:?}");
        for &v in &values {
            assert_eq!(from_key(order_key(v)), v);
        }
        let mut keys: Vec<u32> = [3.0f32, -1.0, 10.0, 2.0, 2.5]
            .iter()
            .map(|&v| order_key(v))
            .collect();
        let (median, mad) = median_and_mad(&mut keys);
        // Median 2.5; absolute deviations 0.5, 3.5, 7.5, 0.5, 0 → median 0.5.
        assert_eq!((median, mad), (2.5, 1.4826 * 0.5));
    }
}
