//! Parsers for numeric flags, so a value that cannot mean anything (a rate of 0, a share of
//! 2, NaN) is a usage error when the command starts, not a panic or a refusal after the work.

fn number(text: &str) -> Result<f64, String> {
    let v: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("{text:?} is not a number"))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("{text:?} is not a finite number"))
    }
}

/// A finite number above 0 (rates, durations, speeds, tolerances).
pub(super) fn positive(text: &str) -> Result<f64, String> {
    let v = number(text)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(format!("{v} is not above 0"))
    }
}

/// A finite number of at least 0 (windows, distances).
pub(super) fn non_negative(text: &str) -> Result<f64, String> {
    let v = number(text)?;
    if v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("{v} is below 0"))
    }
}

/// [`non_negative`] as `f32`.
pub(super) fn non_negative_f32(text: &str) -> Result<f32, String> {
    non_negative(text).map(|v| v as f32)
}

/// A share, from 0 to 1.
pub(super) fn share(text: &str) -> Result<f64, String> {
    let v = number(text)?;
    if (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("{v} is not a share from 0 to 1"))
    }
}

/// An input limit in MB: a whole number of at least 1 (0 would refuse every file).
pub(super) fn input_limit_mb(text: &str) -> Result<u64, String> {
    match text.trim().parse::<u64>() {
        Ok(0) => Err("0 MB would refuse every file: give at least 1".into()),
        Ok(mb) => Ok(mb),
        Err(_) => Err(format!("{text:?} is not a whole number of MB")),
    }
}

/// Any finite number.
pub(super) fn finite(text: &str) -> Result<f64, String> {
    number(text)
}

#[cfg(test)]
mod tests {
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
}
