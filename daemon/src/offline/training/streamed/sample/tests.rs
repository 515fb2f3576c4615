use super::*;

fn take(frames: usize, value: f32) -> ModelFrames {
    ModelFrames {
        xyz: (0..frames * 3).map(|i| value + i as f32).collect(),
        missing: vec![false; frames],
        markers: 1,
    }
}

fn push(s: &mut Sampler, i: usize, t: &ModelFrames) {
    s.push(i, t.frames(), &|r| ModelFrames {
        xyz: t.xyz[r.start * 3..r.end * 3].to_vec(),
        missing: t.missing[r].to_vec(),
        markers: 1,
    });
}

#[test]
fn a_session_within_the_budget_comes_back_whole() {
    let mut s = Sampler::new(10_000, 1_537.0);
    let takes = [take(500, 0.0), take(37, 1e5), take(1_000, 2e5)];
    for (i, t) in takes.iter().enumerate() {
        push(&mut s, i, t);
    }
    let out = s.finish(&[0]);
    assert_eq!(out.len(), 3);
    for (got, want) in out.iter().zip(&takes) {
        assert_eq!(got.xyz, want.xyz);
    }
}

/// 200 takes of 1,000 frames sampled with a budget of 5,000, the session guessed to have
/// `expected` frames: the first stride and the frames kept.
fn long_session(expected: f64) -> (usize, usize) {
    let mut s = Sampler::new(5_000, expected);
    let first = s.stride;
    for i in 0..200 {
        push(&mut s, i, &take(1_000, i as f32 * 1e4));
    }
    let frames = s.finish(&[0]).iter().map(ModelFrames::frames).sum();
    (first, frames)
}

#[test]
fn a_guessed_length_keeps_about_the_target_share() {
    // 200,000 frames guessed: 833 segments of 240 frames, 15.6 of them aimed at. (The
    // takes' last segments are 40 frames: there are 1,000 segments of 200 on average.)
    let (stride, guessed) = long_session(200_000.0);
    assert_eq!(stride, 53);
    assert!((3_000..=4_500).contains(&guessed), "{guessed}");
    // Doubling alone lands where the stride last doubled: here at the bottom.
    let (stride, doubled) = long_session(0.0);
    assert_eq!(stride, 1);
    assert!(doubled < guessed, "{doubled} vs {guessed}");
    // A guess 4x short still keeps the budget by doubling.
    let (_, short_guess) = long_session(50_000.0);
    assert!((2_500..=5_000).contains(&short_guess), "{short_guess}");
}

#[test]
fn a_long_session_is_sampled_evenly_within_the_budget() {
    let mut s = Sampler::new(5_000, 0.0);
    for i in 0..400 {
        push(&mut s, i, &take(1_000, i as f32 * 1e4));
    }
    let stride = s.stride;
    let out = s.finish(&[0]);
    let frames: usize = out.iter().map(ModelFrames::frames).sum();
    assert!((2_500..=5_000).contains(&frames), "{frames} frames");
    // Kept segments are evenly spaced, from the first take to within one stride (of 5
    // segments a take) of the last.
    assert!(stride > 1);
    assert_eq!(out[0].xyz[0], 0.0);
    let last_take = out.last().expect("kept").xyz[0] / 1e4;
    assert!(
        last_take >= (400 - stride / 5 - 1) as f32,
        "last take {last_take}, stride {stride}"
    );
}
