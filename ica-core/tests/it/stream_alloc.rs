//! The streaming kernels allocate nothing per frame: after a warm-up, pushing 10,000 frames
//! through moments, whitening, the subsample, the FastICA update and the source moments
//! allocates nothing at all, at 5 channels as at 327. faer's products keep their packing
//! buffers per thread (matrixmultiply, before it, allocated one per call).

use ica_core::fastica::{SourceMoments, Subsample, SubsamplePlan, UpdateAccumulator};
use ica_core::fit::{mixture, Contrast, FitData};
use ica_core::whiten::{Components, Moments, Whitener};
use nalgebra::DMatrix;

const FRAMES: usize = 10_000;
const CHUNK: usize = 1_000;

/// Allocations made pushing every chunk of `samples` (`channels` wide) through every kernel,
/// after one warm-up round on the first chunk.
fn allocations(samples: &[f32], channels: usize, m: usize) -> u64 {
    let data = FitData::new(samples, channels).expect("whole frames");
    let mut moments = Moments::new(channels);
    moments.add_chunk(&data).expect("finite");
    let whitener = Whitener::from_moments(&moments, Components::Fixed(m)).expect("whitens");
    let w = DMatrix::<f64>::identity(m, m);
    let mut acc = UpdateAccumulator::new(&w, Contrast::LogCosh);
    let mut sums = SourceMoments::new(&w, Contrast::LogCosh);
    let mut sub = Subsample::new(m, 2 * FRAMES, SubsamplePlan::Strided(4));
    let (mut z, mut scratch) = (Vec::<f32>::new(), Vec::new());
    let mut round = |first: usize, last: usize| {
        for s in (first..last).step_by(CHUNK) {
            let chunk = data.slice_frames(s, s + CHUNK);
            moments.add_chunk(&chunk).expect("finite");
            whitener
                .whiten_into(&chunk, &mut z, &mut scratch)
                .expect("whitens");
            sub.push(&z).expect("whole frames");
            acc.add_chunk(&z).expect("whole frames");
            sums.add_chunk(&z).expect("whole frames");
        }
    };
    round(0, CHUNK);
    allocation_counter::measure(|| round(0, FRAMES)).count_total
}

#[test]
fn streaming_kernels_do_not_allocate_per_frame() {
    for (channels, m, seed) in [(5, 3, 1), (327, 20, 2)] {
        let mix = mixture::face_like(FRAMES, channels, m, 0.2, seed);
        let n = allocations(&mix.samples, channels, m);
        assert_eq!(
            n, 0,
            "{FRAMES} frames at {channels} channels allocated {n} times"
        );
    }
}
