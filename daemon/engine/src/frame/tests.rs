//! Tests of the shared frame path.

use super::*;

#[test]
fn non_finite_samples_and_spikes_become_missing() {
    let plain = CaptureSettings::default();
    let mut prep = FramePrep::new(3, 100.0, &plain);
    let mut xyz = [1.0_f32; 9];
    let out = prep
        .prepare(&xyz, &[false, true, false])
        .expect("sizes match");
    assert_eq!(out.missing, &[false, true, false]);
    xyz[7] = f32::NAN;
    let out = prep
        .prepare(&xyz, &[false, false, false])
        .expect("sizes match");
    assert_eq!(
        (out.missing, out.info.glitches),
        (&[false, false, true][..], 0)
    );

    // 1 m/s at 100 Hz: 10 mm a frame.
    let limited = CaptureSettings {
        max_speed_mm_s: Some(1_000.0),
        ..CaptureSettings::default()
    };
    let mut prep = FramePrep::new(3, 100.0, &limited);
    let mut xyz = [0.0_f32; 9];
    prep.prepare(&xyz, &[false; 3]).expect("sizes match");
    xyz[3] = 50.0;
    xyz[6] = 5.0;
    let out = prep.prepare(&xyz, &[false; 3]).expect("sizes match");
    assert_eq!(
        (out.missing, out.info.glitches),
        (&[false, true, false][..], 1)
    );

    // Steady frames take the two-pass path; it must decide exactly as the per-marker
    // loop: 6 mm on each axis is 10.4 mm in space (rejected), 5.7 mm is 9.9 mm (kept),
    // 9.9 mm along one axis is kept by the loop after the fast test declines.
    let mut prep = FramePrep::new(3, 100.0, &limited);
    let mut xyz = [0.0_f32; 9];
    for _ in 0..3 {
        let out = prep.prepare(&xyz, &[false; 3]).expect("sizes match");
        assert_eq!(out.info.glitches, 0);
    }
    xyz[0..3].fill(5.7);
    xyz[3] = 9.9;
    let out = prep.prepare(&xyz, &[false; 3]).expect("sizes match");
    assert_eq!(out.info.glitches, 0);
    prep.prepare(&xyz, &[false; 3]).expect("sizes match");
    xyz[0..3].iter_mut().for_each(|v| *v += 5.0);
    xyz[6..9].fill(6.0);
    let out = prep.prepare(&xyz, &[false; 3]).expect("sizes match");
    assert_eq!(
        (out.missing, out.info.glitches),
        (&[false, false, true][..], 1)
    );

    // Balls of radius 2 mm around the origin; a missing marker is not counted twice.
    let bounded = CaptureSettings {
        bounds: Some(ica_core::model::MarkerBounds {
            centre: vec![[0.0; 3]; 3],
            radius_mm: vec![2.0; 3],
        }),
        ..CaptureSettings::default()
    };
    let mut prep = FramePrep::new(3, 100.0, &bounded);
    let xyz = [1.0, 1.0, 1.0, 1.5, 1.5, 0.0, 9.0, 9.0, 9.0];
    let out = prep
        .prepare(&xyz, &[false, false, true])
        .expect("sizes match");
    assert_eq!(
        (out.missing, out.info.glitches),
        (&[false, true, true][..], 1)
    );
}
