use super::*;

#[test]
fn numbers_that_cannot_mean_anything_are_refused() {
    assert_eq!(positive("120"), Ok(120.0));
    for bad in ["0", "-1", "nan", "inf", "fast", ""] {
        assert!(positive(bad).is_err(), "{bad}");
    }
    assert_eq!(input_limit_mb("8192"), Ok(8192));
    for bad in ["0", "-1", "1.5", "lots"] {
        assert!(input_limit_mb(bad).is_err(), "{bad}");
    }
    assert_eq!(non_negative("0"), Ok(0.0));
    assert!(non_negative("-0.5").is_err());
    assert!(non_negative("NaN").is_err());
    assert_eq!(share("0.25"), Ok(0.25));
    for bad in ["2", "-0.1", "nan"] {
        assert!(share(bad).is_err(), "{bad}");
    }
    assert_eq!(finite("-3.5"), Ok(-3.5));
    assert!(finite("-inf").is_err());
}
