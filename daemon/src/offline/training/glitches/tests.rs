use super::*;

/// Frames of `n` markers wandering from place to place, some missing, one far glitch.
fn frames(count: usize, n: usize) -> (Vec<f32>, Vec<bool>) {
    let (mut xyz, mut missing) = (Vec::new(), Vec::new());
    let mut state = 12345u64;
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 33) as f64 / (1u64 << 31) as f64) as f32 - 0.5
    };
    for f in 0..count {
        for m in 0..n {
            let base = [m as f32 * 10.0, (f % 50) as f32 * 0.3, -(m as f32)];
            xyz.extend(base.map(|b| b + 5.0 * next()));
            missing.push((f * 7 + m * 3) % 11 == 0);
        }
    }
    xyz[3 * n * (count / 2)] += 400.0;
    (xyz, missing)
}

/// The definitions written plainly: medians of each axis, percentile of the distances,
/// percentile of the speeds, all in f64.
fn plain_bounds(xyz: &[f32], missing: &[bool], n: usize) -> MarkerBounds {
    let frames = missing.len() / n;
    let (mut centre, mut radius_mm) = (Vec::new(), Vec::new());
    for m in 0..n {
        let present: Vec<usize> = (0..frames).filter(|&f| !missing[f * n + m]).collect();
        let at = |f: usize, a: usize| f64::from(xyz[(f * n + m) * 3 + a]);
        let mut c = [0.0; 3];
        for (a, slot) in c.iter_mut().enumerate() {
            let mut v: Vec<f64> = present.iter().map(|&f| at(f, a)).collect();
            *slot = quantile(&mut v, 0.5);
        }
        let mut d: Vec<f64> = present
            .iter()
            .map(|&f| {
                (0..3)
                    .map(|a| (at(f, a) - c[a]).powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
            .collect();
        centre.push(c);
        radius_mm.push((quantile(&mut d, 0.99) * BOUNDS_FACTOR).max(MIN_BOUNDS_MM));
    }
    MarkerBounds { centre, radius_mm }
}

#[test]
fn bounds_and_speed_are_the_plain_definitions_value_for_value() {
    let n = 7;
    let (xyz, missing) = frames(900, n);
    let bounds = marker_bounds(&xyz, &missing, n);
    assert_eq!(bounds, plain_bounds(&xyz, &missing, n));
    let past_floor = bounds
        .radius_mm
        .iter()
        .filter(|&&r| r > MIN_BOUNDS_MM)
        .count();
    assert!(
        past_floor > n / 2,
        "the test must reach past the floor: {bounds:?}"
    );
    let takes: Vec<ModelFrames> = [400, 500]
        .iter()
        .scan(0, |start, &len| {
            let r = *start..*start + len;
            *start += len;
            Some(ModelFrames {
                xyz: xyz[r.start * n * 3..r.end * n * 3].to_vec(),
                missing: missing[r.start * n..r.end * n].to_vec(),
                markers: n,
            })
        })
        .collect();
    let mut speeds = Vec::new();
    for take in &takes {
        for f in 1..take.frames() {
            let ((a, ma), (b, mb)) = (take.frame(f - 1), take.frame(f));
            for m in (0..n).filter(|&m| !ma[m] && !mb[m]) {
                let d2: f32 = (0..3).map(|k| (b[m * 3 + k] - a[m * 3 + k]).powi(2)).sum();
                speeds.push(f64::from(d2.sqrt()) * 120.0);
            }
        }
    }
    let plain = (quantile(&mut speeds, 0.999) * AUTO_SPEED_FACTOR).max(MIN_AUTO_SPEED_MM_S);
    let got = auto_speed(&xyz, &missing, &takes, n, 120.0).expect("speeds");
    assert_eq!(got.to_bits(), plain.to_bits(), "{got} vs {plain}");
    assert!(
        got > MIN_AUTO_SPEED_MM_S,
        "the test must reach past the floor: {got}"
    );
}
