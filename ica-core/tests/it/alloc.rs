//! The frame path allocates nothing: project + edit + resynthesise, full and masked frames,
//! counted by a global allocator (allocation-counter's, so no `unsafe` here: the workspace
//! forbids it).

use ica_core::{FrameEdit, IcaModel, Projector, TrainReport};
use nalgebra::DMatrix;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const MARKERS: usize = 109;
const N: usize = MARKERS * 3;
const M: usize = 20;
const FRAMES: usize = 10_000;

fn model(rng: &mut ChaCha8Rng) -> IcaModel {
    let report = TrainReport::untrained(N, M);
    let mixing = DMatrix::from_fn(N, M, |_, _| rng.random_range(-1.0..1.0));
    let labels = (0..MARKERS).map(|i| format!("m{i}")).collect();
    let mean = (0..N).map(|_| rng.random_range(900.0..1100.0)).collect();
    IcaModel::new(labels, 120.0, mean, mixing, report).expect("random mixing has full rank")
}

#[test]
fn frame_path_does_not_allocate() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let model = model(&mut rng);
    let mut projector = Projector::new(&model);
    let mut edit = FrameEdit::identity(M);
    edit.set_offset(2, 1.5).expect("in range");
    edit.set_gain(4, 0.5).expect("in range");
    edit.set_override(7, Some(-1.0)).expect("in range");
    // Inputs prepared up front: frames, and masks covering every path (none, a few markers,
    // the mouth block = ill-conditioned is possible, nearly everything = held, a NaN).
    let frames: Vec<Vec<f32>> = (0..16)
        .map(|_| {
            (0..N)
                .map(|j| model.mean()[j] as f32 + rng.random_range(-5.0..5.0))
                .collect()
        })
        .collect();
    let mut masks = vec![vec![false; MARKERS]; 4];
    for i in (0..MARKERS).step_by(5) {
        masks[1][i] = true;
    }
    masks[2][40..52].fill(true);
    masks[3].fill(true);
    masks[3][..5].fill(false);
    let mut with_nan = frames[0].clone();
    with_nan[10] = f32::NAN;
    let (mut out_x, mut out_u) = (vec![0.0_f32; N], vec![0.0_f32; M]);

    let mut run = |count: usize, projector: &mut Projector| {
        let mut held = 0;
        for f in 0..count {
            let x = if f % 97 == 0 {
                &with_nan
            } else {
                &frames[f % frames.len()]
            };
            let mask = (f % 5 != 0).then(|| masks[f % masks.len()].as_slice());
            let status = projector
                .process_into(x, mask, &edit, &mut out_x, &mut out_u)
                .expect("buffers sized from the model");
            held += usize::from(status.held);
        }
        held
    };
    run(100, &mut projector);
    let mut held = 0;
    let info = allocation_counter::measure(|| {
        held = run(FRAMES, &mut projector);
    });
    assert!(held > 0, "the held path was exercised");
    assert!(out_x.iter().all(|v| v.is_finite()));
    assert_eq!(info.count_total, 0, "{FRAMES} frames allocated: {info:?}");
}
