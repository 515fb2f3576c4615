use crate::input::FitData;
use crate::mixture;
use crate::whiten::{whiten, Components};

/// The PCA axes' signs follow the data, not the eigen-solver's rounding.
#[test]
fn one_ulp_does_not_flip_an_axis() {
    let mix = mixture::face_like(4_000, 60, 6, 0.2, 3);
    let data = FitData::new(&mix.samples, 60).expect("whole frames");
    let a = whiten(&data, Components::Fixed(6)).expect("whitens");
    for at in [12_345, 99_999, 200_001] {
        let mut x = mix.samples.clone();
        x[at] = f32::from_bits(x[at].to_bits() + 1);
        let nudged = FitData::new(&x, 60).expect("whole frames");
        let b = whiten(&nudged, Components::Fixed(6)).expect("whitens");
        for k in 0..6 {
            let cos = a.basis.column(k).dot(&b.basis.column(k));
            assert!(cos > 1.0 - 1e-9, "sample {at}: axis {k} turned, cos {cos}");
        }
    }
}
