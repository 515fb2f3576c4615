//! The CSV preamble: optional `# key=value` comment lines, then the column header.

use crate::error::ReadError;
use crate::Units;

/// What the `#` comment lines declare.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Meta {
    /// `rate_hz=...`.
    pub(crate) rate_hz: Option<f64>,
    /// `units=...`.
    pub(crate) units: Option<Units>,
}

/// Reads `rate_hz=` and `units=` from a comment line (`#` already seen); other words are free
/// text and ignored.
///
/// # Errors
/// A `rate_hz` that is not a positive finite number, or unknown units.
pub(crate) fn parse_comment(line: usize, text: &str, meta: &mut Meta) -> Result<(), ReadError> {
    let body = text.trim_start().trim_start_matches('#');
    for word in body.split_whitespace() {
        match word.split_once('=') {
            Some(("rate_hz", value)) => {
                let rate = value
                    .parse::<f64>()
                    .ok()
                    .filter(|r| r.is_finite() && *r > 0.0);
                let rate = rate.ok_or_else(|| ReadError::BadHeader {
                    line,
                    expected: "a positive `rate_hz=` value",
                    found: word.to_owned(),
                })?;
                meta.rate_hz = Some(rate);
            }
            Some(("units", value)) => {
                let units =
                    Units::parse(value).ok_or_else(|| ReadError::UnknownUnits(value.to_owned()))?;
                meta.units = Some(units);
            }
            _ => {}
        }
    }
    Ok(())
}

/// Marker labels from `frame,time,<label>_x,<label>_y,<label>_z,...`, and the number of extra
/// columns between `time` and the markers (1 for a `timecode` column, else 0).
///
/// Labels may contain underscores: each column is split at its last `_`. Cells are trimmed and
/// may be wrapped in double quotes, as spreadsheets write them.
///
/// # Errors
/// [`ReadError::BadHeader`] when the line does not start `frame,time` or the marker columns are
/// not a multiple of three; [`ReadError::BadCell`] naming the column whose label or axis suffix
/// breaks the `_x`, `_y`, `_z` sequence.
pub(crate) fn parse_header(line: usize, text: &str) -> Result<(Vec<String>, usize), ReadError> {
    let mut cells: Vec<&str> = text.split(',').map(unquote).collect();
    let starts_right = cells.len() >= 2
        && cells[0].eq_ignore_ascii_case("frame")
        && cells[1].eq_ignore_ascii_case("time");
    // A live recording's `timecode` column (issue 16) comes right after `time`.
    let extra = usize::from(
        cells
            .get(2)
            .is_some_and(|c| c.eq_ignore_ascii_case("timecode")),
    );
    if extra == 1 {
        cells.remove(2);
    }
    if !starts_right || (cells.len() - 2) % 3 != 0 {
        return Err(ReadError::BadHeader {
            line,
            expected: "a `frame,time,<label>_x,<label>_y,<label>_z,...` header",
            found: text.to_owned(),
        });
    }
    let mut labels = Vec::with_capacity((cells.len() - 2) / 3);
    for (m, triple) in cells[2..].chunks(3).enumerate() {
        let mut label = "";
        for (axis, (cell, suffix)) in triple.iter().zip(["x", "y", "z"]).enumerate() {
            let split = cell.rsplit_once('_');
            let ok = match split {
                Some((name, s)) => s.eq_ignore_ascii_case(suffix) && (axis == 0 || name == label),
                None => false,
            };
            if !ok {
                return Err(ReadError::BadCell {
                    line,
                    column: 3 + extra + 3 * m + axis,
                    field: "header".to_owned(),
                    expected: [
                        "`<label>_x`",
                        "`<label>_y` after `<label>_x`",
                        "`<label>_z`",
                    ][axis],
                    found: (*cell).to_owned(),
                });
            }
            if axis == 0 {
                label = split.map_or("", |(name, _)| name);
            }
        }
        labels.push(label.to_owned());
    }
    Ok((labels, extra))
}

/// A header cell without surrounding spaces or double quotes.
fn unquote(cell: &str) -> &str {
    let cell = cell.trim();
    cell.strip_prefix('"')
        .and_then(|c| c.strip_suffix('"'))
        .unwrap_or(cell)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // a failed unwrap is a failed test
mod tests;
