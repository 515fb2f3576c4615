use super::*;
use crate::model::SpaceTarget;

#[test]
fn an_old_model_reads_as_a_one_dimensional_space() {
    let old = EmotionLevels {
        component: Some(2),
        levels: [("happy".to_string(), 1.5), ("sad".to_string(), -0.5)].into(),
        ..EmotionLevels::default()
    };
    assert_eq!(old.space_components(), vec![2]);
    assert_eq!(old.point("happy"), Some(vec![1.5]));
    assert_eq!(old.blend(&[("happy", 1.0), ("sad", 1.0)]), Ok(vec![0.5]));
    assert!(matches!(
        old.blend(&[("angry", 1.0)]),
        Err(BlendError::UnknownEmotion { .. })
    ));
    assert!(matches!(
        old.blend(&[("happy", -1.0)]),
        Err(BlendError::BadWeight { .. })
    ));
}

#[test]
fn points_blend_in_the_space() {
    let point = |level: Vec<f64>| EmotionPoint {
        spread: vec![0.0; level.len()],
        level,
        takes: 1,
    };
    let space = EmotionLevels {
        component: Some(0),
        levels: BTreeMap::new(),
        components: vec![0, 3],
        persistence: vec![],
        axes: vec![],
        moves: vec![],
        conditioning: None,
        points: [
            ("sad".to_string(), point(vec![-1.0, 2.0])),
            ("angry".to_string(), point(vec![1.0, 0.0])),
        ]
        .into(),
    };
    assert_eq!(space.dims(), 2);
    assert_eq!(
        space.blend(&[("sad", 0.5), ("angry", 0.5)]),
        Ok(vec![0.0, 1.0])
    );
}

#[test]
fn a_persistent_component_keeps_the_take_s_own_offset() {
    let point = |level: Vec<f64>| EmotionPoint {
        spread: vec![0.1, 0.1],
        level,
        takes: 4,
    };
    let space = EmotionLevels {
        component: Some(0),
        levels: BTreeMap::new(),
        components: vec![0, 1],
        persistence: vec![0.0, 1.0],
        axes: vec![],
        moves: vec![],
        conditioning: None,
        points: [
            ("happy".to_string(), point(vec![1.0, 0.0])),
            ("sad".to_string(), point(vec![-1.0, 0.5])),
        ]
        .into(),
    };
    let mut t = SpaceTarget::new(&space, 2);
    let mut out = [0.0f32; 2];
    // A happy take whose second component sits 2.0 above happy's level (its sentence).
    t.target_into(&[1.05, 2.0], &[-1.0, 0.5], &mut out);
    assert!((out[0] + 1.0).abs() < 1e-6, "{out:?}");
    assert!((out[1] - 2.5).abs() < 1e-3, "{out:?}");
}

#[test]
fn fitted_axes_read_and_move_components() {
    // One axis along c0 + c1 over three components; moving by 2 along it changes both.
    let s = 0.5f64.sqrt();
    let space = EmotionLevels {
        axes: vec![vec![s, s, 0.0]],
        moves: vec![vec![s, s, 0.0]],
        points: [(
            "happy".to_string(),
            EmotionPoint {
                level: vec![1.0],
                spread: vec![0.1],
                takes: 3,
            },
        )]
        .into(),
        ..EmotionLevels::default()
    };
    assert_eq!(space.dims(), 1);
    let t = SpaceTarget::new(&space, 3);
    let mut at = [0.0f32];
    t.coordinates_into(&[1.0, 1.0, 5.0], &mut at);
    assert!((at[0] - 2.0 * s as f32).abs() < 1e-6);
    let mut u = [0.0f32; 3];
    t.move_into(&[2.0], 0.5, &mut u);
    assert!((u[0] - s as f32).abs() < 1e-6 && (u[1] - s as f32).abs() < 1e-6 && u[2] == 0.0);
    // Without axes, the components are the axes.
    let plain = EmotionLevels {
        components: vec![2],
        ..EmotionLevels::default()
    };
    assert_eq!(
        plain.axis_matrices(3),
        (vec![0.0, 0.0, 1.0], vec![0.0, 0.0, 1.0])
    );
}
