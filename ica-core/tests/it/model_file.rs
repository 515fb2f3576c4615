//! The model file format: the golden file pins the layout; broken files fail with the variant
//! that names what is wrong.

use ica_core::{IcaModel, ModelError, Role, FORMAT_VERSION};
use serde_json::{json, Value};

const GOLDEN: &str = include_str!("../fixtures/golden-model-v1.json");

fn golden_value() -> Value {
    serde_json::from_str(GOLDEN).expect("golden file is json")
}

fn load_value(v: &Value) -> Result<IcaModel, ModelError> {
    IcaModel::load(v.to_string().as_bytes())
}

#[test]
fn golden_file_loads_with_its_contents() {
    let model = IcaModel::load(GOLDEN.as_bytes()).expect("golden file loads");
    assert_eq!(FORMAT_VERSION, 1);
    assert_eq!(model.labels(), &["forehead", "lip_upper", "lip_lower"]);
    assert_eq!(
        (model.channels(), model.markers(), model.components()),
        (9, 3, 2)
    );
    assert_eq!(model.rate_hz(), 120.0);
    assert_eq!(model.mean()[2], 1040.25);
    assert_eq!(model.mixing()[(7, 1)], -3.0);
    assert_eq!(model.mixing()[(4, 0)], 0.75);
    assert_eq!(model.roles(), &[Role::Emotion, Role::Speech]);
    assert_eq!(model.emotion().component, Some(0));
    assert_eq!(model.emotion().levels.get("happy"), Some(&1.5));
    assert_eq!(model.emotion().levels.get("frustrated"), Some(&-1.25));
    assert_eq!(model.variance_kept(), 0.97);
    assert_eq!(model.report().restarts[0].seed, 7);
    assert_eq!(model.report().frames_used, 588);
    let wm = model.unmixing() * model.mixing();
    assert!((wm - nalgebra::DMatrix::<f64>::identity(2, 2)).amax() < 1e-12);
}

#[test]
fn golden_file_resaves_byte_for_byte() {
    let model = IcaModel::load(GOLDEN.as_bytes()).expect("golden file loads");
    let mut out = Vec::new();
    model.save(&mut out).expect("vec writer");
    assert_eq!(String::from_utf8(out).expect("utf-8"), GOLDEN);
}

#[test]
fn save_load_round_trip_is_exact_for_awkward_floats() {
    let model = IcaModel::load(GOLDEN.as_bytes()).expect("golden file loads");
    let mut v = golden_value();
    // Values with 17 significant digits exercise exact float parsing.
    v["mean"][0] = json!(0.1 + 0.2);
    v["mean"][3] = json!(-1_234.567_890_123_456);
    let edited = load_value(&v).expect("still valid");
    let mut out = Vec::new();
    edited.save(&mut out).expect("vec writer");
    let back = IcaModel::load(out.as_slice()).expect("reloads");
    assert_eq!(back, edited);
    assert_eq!(back.mean()[0].to_bits(), (0.1_f64 + 0.2).to_bits());
    assert_ne!(back, model);
}

#[test]
fn optional_fields_default_and_unknown_fields_are_ignored() {
    let mut v = golden_value();
    let obj = v.as_object_mut().expect("top level is an object");
    obj.remove("roles");
    obj.remove("emotion");
    obj.insert("head".into(), json!({"reference_markers": ["forehead"]}));
    let model = load_value(&v).expect("older and newer files load");
    assert_eq!(model.roles(), &[Role::Unknown, Role::Unknown]);
    assert_eq!(model.emotion().component, None);
    assert!(model.emotion().levels.is_empty());
}

fn load_err(edit: impl FnOnce(&mut Value)) -> ModelError {
    let mut v = golden_value();
    edit(&mut v);
    load_value(&v).expect_err("edited file must be rejected")
}

#[test]
fn version_is_checked_first() {
    let e = load_err(|v| {
        v["format_version"] = json!(2);
        v["mixing"] = json!("a future layout");
    });
    assert!(
        matches!(
            e,
            ModelError::UnsupportedVersion {
                found: 2,
                supported: 1
            }
        ),
        "{e}"
    );
    assert_eq!(
        e.to_string(),
        "model format version 2 is not supported (this build reads version 1)"
    );
    let e = load_err(|v| {
        v.as_object_mut().expect("object").remove("format_version");
    });
    assert!(matches!(e, ModelError::MissingVersion), "{e}");
}

#[test]
fn shapes_and_labels_are_checked() {
    let e = load_err(|v| v["mixing"][3] = json!([1.0, 2.0, 3.0]));
    assert!(
        matches!(
            e,
            ModelError::RaggedRow {
                what: "mixing",
                row: 3,
                expected: 2,
                got: 3
            }
        ),
        "{e}"
    );
    let e = load_err(|v| v["mean"] = json!([1.0, 2.0]));
    assert!(
        matches!(
            e,
            ModelError::ShapeMismatch {
                what: "mean",
                expected: (9, 1),
                got: (2, 1)
            }
        ),
        "{e}"
    );
    let e = load_err(|v| v["unmixing"] = json!([vec![0.0; 9]]));
    assert!(
        matches!(
            e,
            ModelError::ShapeMismatch {
                what: "unmixing",
                expected: (2, 9),
                got: (1, 9)
            }
        ),
        "{e}"
    );
    let e = load_err(|v| v["labels"] = json!(["a", "b"]));
    assert!(
        matches!(
            e,
            ModelError::LabelCount {
                channels: 9,
                expected: 3,
                got: 2
            }
        ),
        "{e}"
    );
    let e = load_err(|v| v["labels"][2] = json!("forehead"));
    assert!(
        matches!(
            e,
            ModelError::DuplicateLabel {
                first: 0,
                second: 2,
                ..
            }
        ),
        "{e}"
    );
    assert_eq!(
        e.to_string(),
        "marker label \"forehead\" appears twice, at 0 and 2"
    );
    let e = load_err(|v| v["roles"] = json!(["speech"]));
    assert!(
        matches!(
            e,
            ModelError::ShapeMismatch {
                what: "roles",
                expected: (2, 1),
                got: (1, 1)
            }
        ),
        "{e}"
    );
    let e = load_err(|v| v["report"]["components"] = json!(3));
    assert!(
        matches!(
            e,
            ModelError::ReportMismatch {
                what: "components",
                expected: 2,
                got: 3
            }
        ),
        "{e}"
    );
}

#[test]
fn emotion_component_and_unmixing_are_checked() {
    let e = load_err(|v| v["emotion"]["component"] = json!(2));
    assert!(
        matches!(
            e,
            ModelError::ComponentOutOfRange {
                index: 2,
                components: 2,
                ..
            }
        ),
        "{e}"
    );
    let e = load_err(|v| v["unmixing"][0][1] = json!(0.5));
    assert!(
        matches!(
            e,
            ModelError::NotPseudoInverse {
                check: "W·M = I",
                ..
            }
        ),
        "{e}"
    );
    let e = load_err(|v| v["rate_hz"] = json!(-120.0));
    assert!(matches!(e, ModelError::InvalidRate { .. }), "{e}");
}

#[test]
fn malformed_json_reports_line_and_column() {
    let broken = GOLDEN.replace("\"rate_hz\": 120.0,", "\"rate_hz\": 120.0,,");
    let e = IcaModel::load(broken.as_bytes()).expect_err("syntax error");
    assert!(matches!(e, ModelError::Malformed { line: 4, .. }), "{e}");
    let wrong_type = GOLDEN.replace("\"rate_hz\": 120.0", "\"rate_hz\": \"fast\"");
    let e = IcaModel::load(wrong_type.as_bytes()).expect_err("type error");
    assert!(matches!(e, ModelError::Malformed { line: 4, .. }), "{e}");
    assert!(
        e.to_string().starts_with("malformed model file at line 4"),
        "{e}"
    );
}

/// Issue 34: a fitted emotion space (axes over every component, the moves along them, points
/// over the axes, how it was found) round-trips; the golden file (no axes) still reads as one
/// component per axis; misshapen axes are refused.
#[test]
fn fitted_emotion_axes_round_trip_and_misshapen_ones_are_refused() {
    let golden = IcaModel::load(GOLDEN.as_bytes()).expect("golden file loads");
    assert_eq!(golden.emotion().dims(), 1);
    assert_eq!(
        golden.emotion().axis_matrices(2),
        (vec![1.0, 0.0], vec![1.0, 0.0])
    );
    let fitted = |v: &mut Value| {
        v["emotion"]["components"] = json!([0]);
        v["emotion"]["axes"] = json!([[0.6, 0.8]]);
        v["emotion"]["moves"] = json!([[0.6, 0.8]]);
        v["emotion"]["points"] = json!({
            "happy": {"level": [1.0], "spread": [0.1], "takes": 3},
            "frustrated": {"level": [-1.5], "spread": [0.2], "takes": 3}
        });
        v["emotion"]["persistence"] = json!([0.25]);
        v["emotion"]["conditioning"] = json!({
            "components": [0], "dims": 1, "condition": 1.0, "unstable": [[0, 0.8]],
            "collinear": [], "ill_conditioned": true, "note": "c0 unstable"
        });
    };
    let mut v = golden_value();
    fitted(&mut v);
    let model = load_value(&v).expect("a fitted space loads");
    let e = model.emotion();
    assert_eq!((e.dims(), e.axis_names()), (1, vec!["e1".to_string()]));
    assert_eq!(e.point("frustrated"), Some(vec![-1.5]));
    assert!(e.conditioning.as_ref().is_some_and(|c| c.ill_conditioned));
    let mut out = Vec::new();
    model.save(&mut out).expect("vec writer");
    assert_eq!(IcaModel::load(out.as_slice()).expect("reloads"), model);
    for field in ["axes", "moves"] {
        let err = load_err(|v| {
            fitted(v);
            v["emotion"][field] = json!([[0.6, 0.8, 0.0]]);
        });
        assert!(
            matches!(err, ModelError::NonFiniteLevel { .. }),
            "{field}: 3 weights for 2 components: {err:?}"
        );
    }
    let err = load_err(|v| {
        fitted(v);
        v["emotion"]["moves"] = json!([]);
    });
    assert!(
        matches!(err, ModelError::NonFiniteLevel { .. }),
        "no moves: {err:?}"
    );
    let err = load_err(|v| {
        fitted(v);
        v["emotion"]["points"]["happy"]["level"] = json!([1.0, 2.0]);
    });
    assert!(
        matches!(err, ModelError::NonFiniteLevel { .. }),
        "2 levels, 1 axis: {err:?}"
    );
}
