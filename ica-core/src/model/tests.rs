use super::*;
use crate::report::TrainReport;

pub(crate) fn report(channels: usize, components: usize) -> TrainReport {
    TrainReport {
        frames_total: 10,
        frames_used: 10,
        channels,
        dead_channels: vec![],
        components,
        variance_kept: 0.95,
        eigenvalues: vec![1.0; channels],
        contrast: "logcosh".into(),
        algorithm: "symmetric".into(),
        tol: 1e-6,
        max_iter: 200,
        restarts: vec![],
        best_restart: 0,
        stability: vec![],
    }
}

pub(crate) fn labels(markers: usize) -> Vec<String> {
    (0..markers).map(|i| format!("M{i}")).collect()
}

/// 2 markers, 2 components, columns not orthogonal so W is not just a scaled transpose.
fn mixing() -> DMatrix<f64> {
    DMatrix::from_row_slice(
        6,
        2,
        &[1.0, 0.5, 0.0, 1.0, 2.0, 0.0, 0.0, 3.0, 1.0, 1.0, -1.0, 0.0],
    )
}

fn model() -> IcaModel {
    IcaModel::new(labels(2), 120.0, vec![10.0; 6], mixing(), report(6, 2)).expect("valid parts")
}

#[test]
fn unmixing_is_the_pseudo_inverse() {
    let m = model();
    let wm = m.unmixing() * m.mixing();
    assert!((wm - DMatrix::<f64>::identity(2, 2)).amax() < 1e-12);
    check_pseudo_inverse(m.mixing(), m.unmixing()).expect("pinv passes its own check");
    assert_eq!((m.channels(), m.markers(), m.components()), (6, 2, 2));
    assert_eq!(m.roles(), &[Role::Unknown, Role::Unknown]);
    assert_eq!(m.variance_kept(), 0.95);
}

#[test]
fn whole_take_round_trip_recovers_components() {
    let m = model();
    let u = DMatrix::from_row_slice(3, 2, &[0.0, 0.0, 1.0, -2.0, 0.25, 4.0]);
    let x = m.resynthesize(&u).expect("m columns");
    assert_eq!(x[(0, 0)], 10.0);
    let back = m.project(&x).expect("n columns");
    assert!((back - u).amax() < 1e-12);
    assert!(matches!(
        m.project(&DMatrix::zeros(3, 5)),
        Err(ModelError::ShapeMismatch {
            what: "take",
            expected: (3, 6),
            got: (3, 5)
        })
    ));
}

#[test]
fn constructor_names_what_is_wrong() {
    let err = |r: Result<IcaModel, ModelError>| r.expect_err("must be rejected");
    let e = err(IcaModel::new(
        labels(3),
        120.0,
        vec![0.0; 6],
        mixing(),
        report(6, 2),
    ));
    assert!(matches!(
        e,
        ModelError::LabelCount {
            channels: 6,
            expected: 2,
            got: 3
        }
    ));
    assert_eq!(
        e.to_string(),
        "model has 6 channels (2 markers) but 3 labels"
    );

    let dup = vec!["A".to_string(), "A".to_string()];
    let e = err(IcaModel::new(
        dup,
        120.0,
        vec![0.0; 6],
        mixing(),
        report(6, 2),
    ));
    assert!(matches!(
        e,
        ModelError::DuplicateLabel {
            first: 0,
            second: 1,
            ..
        }
    ));

    let mut mean = vec![0.0; 6];
    mean[4] = f64::NAN;
    let e = err(IcaModel::new(
        labels(2),
        120.0,
        mean,
        mixing(),
        report(6, 2),
    ));
    assert!(matches!(
        e,
        ModelError::NonFinite {
            what: "mean",
            row: 4,
            col: 0
        }
    ));

    let mut bad = mixing();
    bad[(3, 1)] = f64::INFINITY;
    let e = err(IcaModel::new(
        labels(2),
        120.0,
        vec![0.0; 6],
        bad,
        report(6, 2),
    ));
    assert!(matches!(
        e,
        ModelError::NonFinite {
            what: "mixing",
            row: 3,
            col: 1
        }
    ));

    let e = err(IcaModel::new(
        labels(2),
        0.0,
        vec![0.0; 6],
        mixing(),
        report(6, 2),
    ));
    assert!(matches!(e, ModelError::InvalidRate { .. }));

    let e = err(IcaModel::new(
        labels(2),
        120.0,
        vec![0.0; 5],
        mixing(),
        report(6, 2),
    ));
    assert!(matches!(
        e,
        ModelError::ShapeMismatch {
            what: "mean",
            expected: (6, 1),
            got: (5, 1)
        }
    ));

    let e = err(IcaModel::new(
        labels(2),
        120.0,
        vec![0.0; 6],
        mixing(),
        report(6, 3),
    ));
    assert!(matches!(
        e,
        ModelError::ReportMismatch {
            what: "components",
            expected: 2,
            got: 3
        }
    ));

    let e = err(IcaModel::new(
        labels(1),
        120.0,
        vec![0.0; 4],
        DMatrix::zeros(4, 1),
        report(4, 1),
    ));
    assert!(matches!(e, ModelError::ChannelsNotTriples { channels: 4 }));
}

#[test]
fn rank_deficient_mixing_is_refused() {
    let mut dependent = mixing();
    let first = dependent.column(0).clone_owned();
    dependent.set_column(1, &(first * 2.0));
    let e = IcaModel::new(labels(2), 120.0, vec![0.0; 6], dependent, report(6, 2))
        .expect_err("columns are parallel");
    assert!(matches!(e, ModelError::RankDeficient { .. }), "{e}");
}

#[test]
fn emotion_component_and_levels() {
    let mut m = model();
    m.set_emotion_component(Some(1)).expect("in range");
    assert_eq!(m.roles()[1], Role::Emotion);
    m.set_emotion_component(Some(0)).expect("in range");
    assert_eq!(m.roles(), &[Role::Emotion, Role::Unknown]);
    assert!(matches!(
        m.set_emotion_component(Some(2)),
        Err(ModelError::ComponentOutOfRange {
            index: 2,
            components: 2,
            ..
        })
    ));
    m.set_emotion_level("happy", 1.5).expect("finite");
    assert!(m.set_emotion_level("bad", f64::NAN).is_err());
    assert_eq!(m.emotion().levels.get("happy"), Some(&1.5));
    assert_eq!(m.remove_emotion_level("happy"), Some(1.5));
    m.set_role(1, Role::Speech).expect("in range");
    assert_eq!(m.roles()[1], Role::Speech);
    assert_eq!(m.marker_index("M1"), Some(1));
}

#[test]
fn tampered_unmixing_fails_penrose_checks() {
    let m = model();
    let mut w = m.unmixing().clone();
    w[(0, 0)] += 1e-3;
    assert!(matches!(
        check_pseudo_inverse(m.mixing(), &w),
        Err(ModelError::NotPseudoInverse {
            check: "W·M = I",
            ..
        })
    ));
    // Another left inverse: W + Z with Z·M = 0 keeps W·M = I but is not M⁺.
    let proj = DMatrix::<f64>::identity(6, 6) - m.mixing() * m.unmixing();
    let z = DMatrix::from_fn(2, 6, |i, j| ((i + 2 * j) % 5) as f64 * 0.1) * proj;
    let other = m.unmixing() + z;
    assert!(matches!(
        check_pseudo_inverse(m.mixing(), &other),
        Err(ModelError::NotPseudoInverse {
            check: "M·W symmetric",
            ..
        })
    ));
}
