//! The streaming kernels allocate nothing per frame: after a warm-up, pushing 10,000 frames
//! through moments, whitening, the subsample, the FastICA update and the source moments
//! allocates nothing of ours. matrixmultiply (behind nalgebra's gemm) allocates one packing
//! buffer per call; at small shapes the kernels take their own loops and the count is zero,
//! at 327 channels it is bounded by the gemm calls (per block of frames, never per frame).

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
    // 5 channels, 3 components: every product is below matrixmultiply's threshold.
    let small = mixture::face_like(FRAMES, 5, 3, 0.2, 1);
    let n = allocations(&small.samples, 5, 3);
    assert_eq!(n, 0, "{FRAMES} frames at 5 channels allocated {n} times");
    // 109 markers, 20 components: one packing buffer per gemm call. Per 1,000-frame chunk:
    // moments 8 blocks x 21 channel-block pairs, whitening 4 blocks, update 2, sources 1.
    let face = mixture::face_like(FRAMES, 327, 20, 0.2, 2);
    let n = allocations(&face.samples, 327, 20);
    let gemm_calls = (FRAMES / CHUNK) as u64 * (8 * 21 + 4 + 2 + 1);
    assert!(
        n <= gemm_calls,
        "{FRAMES} frames at 327 channels allocated {n} times"
    );
}
