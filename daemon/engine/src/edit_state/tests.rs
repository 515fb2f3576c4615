use super::*;

const DT: f32 = 1.0 / 120.0;

#[test]
fn settled_alpha_and_gain_equal_frame_edit_bit_for_bit() {
    let mut e = EditState::new(3, &[], 1.0);
    e.set_ramp(0.0);
    e.set_alpha(1, 1.5).expect("in range");
    e.set_gain(2, 0.5).expect("in range");
    let mut fe = ica_core::edit::FrameEdit::identity(3);
    fe.set_offset(1, 1.5).expect("in range");
    fe.set_gain(2, 0.5).expect("in range");
    let mut a = [0.3f32, -0.7, 2.1];
    let mut b = a;
    e.apply(DT, &mut a);
    fe.apply(&mut b).expect("length");
    assert_eq!(a, b);
}

#[test]
fn a_ramp_glides_monotonically_and_arrives_on_time() {
    let mut e = EditState::new(2, &[], 1.0);
    e.set_ramp(0.25);
    e.set_alpha(0, 10.0).expect("in range");
    let mut prev = 0.0;
    let mut max_step = 0.0f32;
    // The frame after the 30th (0.25 s at 120 Hz) sits at the goal.
    for f in 0..32 {
        let mut u = [0.0f32, 0.0];
        e.apply(DT, &mut u);
        assert!(u[0] >= prev, "frame {f}: {} < {prev}", u[0]);
        max_step = max_step.max(u[0] - prev);
        prev = u[0];
        if f == 0 {
            assert!(u[0] < 0.01, "the first frame starts at the old value");
        }
    }
    assert_eq!(prev, 10.0);
    // Smoothstep's steepest slope is 1.5x the linear one: 10 over 30 frames.
    assert!(max_step < 1.5 * 10.0 / 30.0 + 0.05, "step {max_step}");
}

#[test]
fn emotion_edit_moves_the_slow_level_and_keeps_the_fast_motion() {
    let mut e = EditState::new(1, &[0], 1.0);
    e.set_ramp(0.0);
    e.set_target("happy", &[5.0]).expect("emotion component");
    e.set_amount(1.0).expect("emotion component");
    let mut out = Vec::new();
    for f in 0..1200 {
        let speech = (f as f32 * 0.8).sin();
        let mut u = [1.0 + speech];
        e.apply(DT, &mut u);
        out.push((u[0], speech));
    }
    // After 10 low-pass windows the slow part sits at the level, the speech rides on it.
    let tail = &out[1000..];
    let mean = tail.iter().map(|(v, _)| v).sum::<f32>() / tail.len() as f32;
    assert!((mean - 5.0).abs() < 0.05, "mean {mean}");
    let fast = tail
        .iter()
        .map(|(v, s)| (v - mean - s).abs())
        .fold(0.0, f32::max);
    assert!(fast < 0.1, "speech distorted by {fast}");
}

#[test]
fn bypass_glides_back_to_the_input_and_refusals_name_the_value() {
    let mut e = EditState::new(2, &[], 1.0);
    e.set_ramp(0.0);
    e.set_alpha(0, 3.0).expect("in range");
    e.set_ramp(0.1);
    e.set_bypass(true);
    let mut u = [1.0f32, 1.0];
    e.apply(DT, &mut u);
    assert_eq!(u[0], 4.0, "bypass starts from the edited value");
    for _ in 0..20 {
        u = [1.0, 1.0];
        e.apply(DT, &mut u);
    }
    assert_eq!(u, [1.0, 1.0]);
    assert_eq!(
        e.set_gain(5, 1.0),
        Err(EditRefused::Component {
            index: 5,
            components: 2
        })
    );
    assert_eq!(e.set_amount(1.0), Err(EditRefused::NoEmotion));
}

#[test]
fn every_emotion_component_moves_to_its_coordinate_of_the_target() {
    let mut e = EditState::new(3, &[0, 2], 0.5);
    e.set_ramp(0.0);
    assert_eq!(
        e.set_target("sad", &[1.0]),
        Err(EditRefused::Dims {
            expected: 2,
            got: 1
        })
    );
    e.set_target("sad", &[2.0, -1.0]).expect("two levels");
    e.set_amount(1.0).expect("emotion space");
    let mut u = [0.0f32; 3];
    for _ in 0..600 {
        u = [0.3, 7.0, -0.2];
        e.apply(DT, &mut u);
    }
    assert!(
        (u[0] - 2.0).abs() < 1e-3 && (u[2] + 1.0).abs() < 1e-3,
        "{u:?}"
    );
    assert_eq!(u[1], 7.0, "components outside the space are left alone");
}

#[test]
fn fitted_axes_read_the_low_pass_and_move_along_their_components() {
    // One axis reading c0 + c1 (halves) and moving both; c2 outside the space.
    let levels = ica_core::model::EmotionLevels {
        axes: vec![vec![0.5, 0.5, 0.0]],
        moves: vec![vec![1.0, 1.0, 0.0]],
        ..Default::default()
    };
    let mut e = EditState::with_space(3, SpaceTarget::new(&levels, 3), 0.5);
    e.set_ramp(0.0);
    e.set_target("happy", &[3.0]).expect("one level");
    e.set_amount(1.0).expect("emotion space");
    let mut u = [0.0f32; 3];
    for _ in 0..600 {
        u = [1.0, 0.0, 4.0];
        e.apply(DT, &mut u);
    }
    // The take reads 0.5 on the axis; reaching 3 moves c0 and c1 by 2.5 each.
    assert!(
        (u[0] - 3.5).abs() < 1e-3 && (u[1] - 2.5).abs() < 1e-3,
        "{u:?}"
    );
    assert_eq!(u[2], 4.0, "components outside the space are left alone");
}
