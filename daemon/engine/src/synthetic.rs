//! Synthetic models and frames for `emoshift bench`, the benches and the tests: a random
//! well-conditioned model with an emotion component and levels, and frames drawn from it, so a
//! load test needs no files. Seeded and deterministic (a small xorshift, no `rand`).

use ica_core::model::IcaModel;
use ica_core::TrainReport;
use nalgebra::DMatrix;

/// Deterministic pseudo-random numbers in `[-1, 1)`.
#[derive(Debug, Clone)]
pub struct Noise(u64);

impl Noise {
    /// Seeded generator.
    pub fn new(seed: u64) -> Noise {
        Noise(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }

    /// Next value in `[-1, 1)`.
    pub fn next_f64(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// A random model: `markers` markers named `m0..`, `components` components, rate 120 Hz;
/// component 0 is the emotion with levels `neutral` = 0, `happy` = 2, `sad` = −2.
///
/// # Panics
/// Never for `markers ≥ components ≥ 1`: a random mixing matrix has full rank.
pub fn random_model(markers: usize, components: usize, seed: u64) -> IcaModel {
    let mut noise = Noise::new(seed);
    let n = markers * 3;
    let report = TrainReport::untrained(n, components);
    let mixing = DMatrix::from_fn(n, components, |_, _| noise.next_f64() * 5.0);
    let labels = (0..markers).map(|i| format!("m{i}")).collect();
    let mean = (0..n).map(|_| 1000.0 + noise.next_f64() * 100.0).collect();
    let mut model = IcaModel::new(labels, 120.0, mean, mixing, report)
        .expect("a random mixing matrix has full rank");
    model
        .set_emotion_component(Some(0))
        .expect("component 0 exists");
    for (name, level) in [("neutral", 0.0), ("happy", 2.0), ("sad", -2.0)] {
        model
            .set_emotion_level(name, level)
            .expect("finite level and an emotion component");
    }
    model
}

/// [`random_model`] with a two-dimensional emotion space on components 0 and 2: `neutral`
/// (0, 0), `happy` (2, 0), `sad` (−1, −1.5), `angry` (−1, 1.5), spread 0.2 each, and
/// component 2 persisting half its sentence offset.
pub fn random_space_model(markers: usize, components: usize, seed: u64) -> IcaModel {
    let mut model = random_model(markers, components, seed);
    let point = |a: f64, b: f64| ica_core::model::EmotionPoint {
        level: vec![a, b],
        spread: vec![0.2, 0.2],
        takes: 4,
    };
    let points = [
        ("neutral", point(0.0, 0.0)),
        ("happy", point(2.0, 0.0)),
        ("sad", point(-1.0, -1.5)),
        ("angry", point(-1.0, 1.5)),
    ]
    .into_iter()
    .map(|(n, p)| (n.to_string(), p))
    .collect();
    model
        .set_emotion_space(vec![0, 2], 0, points, vec![0.0, 0.5])
        .expect("components 0 and 2 exist");
    model
}

/// The `/mocap/labels` datagram announcing `model`'s markers as layout 0, as a source would.
///
/// # Errors
/// A label the wire format cannot carry (a NUL byte).
pub fn labels_datagram(model: &IcaModel) -> Result<Vec<u8>, protocol::EncodeError> {
    let mut out = Vec::new();
    let labels = protocol::Labels {
        layout_id: 0,
        names: model.labels().to_vec(),
    };
    protocol::encode_labels_into(&labels, &mut out)?;
    Ok(out)
}

/// Frame `f` of a synthetic take on `model`: `mean + M·u(f)` with slow and fast sources, in
/// model marker order, written into `out` (markers × 3).
pub fn frame_into(model: &IcaModel, f: usize, out: &mut [f32]) {
    let t = f as f64 / model.rate_hz();
    let m = model.components();
    let mixing = model.mixing();
    for (c, o) in out.iter_mut().enumerate() {
        let mut v = model.mean()[c];
        for k in 0..m {
            let u = (t * (0.3 + 1.7 * k as f64) + k as f64).sin();
            v += mixing[(c, k)] * u;
        }
        *o = v as f32;
    }
}
