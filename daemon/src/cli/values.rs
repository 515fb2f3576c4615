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
mod tests;
