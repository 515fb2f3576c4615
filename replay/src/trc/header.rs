//! The five TRC header lines: file type, field names, field values, marker names, coordinates.

use std::io::BufRead;

use super::text::Lines;
use crate::error::ReadError;
use crate::Units;

/// What the TRC header says about the data that follows.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Header {
    /// `DataRate`, frames per second.
    pub(crate) rate_hz: f64,
    /// `NumFrames`: data rows the file promises.
    pub(crate) num_frames: usize,
    /// `Units` of every coordinate.
    pub(crate) units: Units,
    /// Marker names, in column order.
    pub(crate) labels: Vec<String>,
    /// `OrigDataStartFrame`, used as the first frame only when there are no data rows.
    pub(crate) start_frame: Option<i64>,
}

/// Reads and checks the header, leaving `lines` at the first line after the coordinate labels.
///
/// # Errors
/// A missing line, a line of the wrong shape, an unparsable required field, unknown units, or a
/// `NumMarkers` that disagrees with the names listed.
pub(crate) fn read_header<R: BufRead>(lines: &mut Lines<R>) -> Result<Header, ReadError> {
    let (n, first) = require(lines, "a `PathFileType` line")?;
    if first.split('\t').next().map(str::trim) != Some("PathFileType") {
        return Err(bad_header(n, "a line starting `PathFileType`", &first));
    }
    let (keys_line, keys) = require(lines, "the `DataRate ... NumFrames NumMarkers Units` line")?;
    let (values_line, values) = require(lines, "the line of header values")?;
    let fields = Fields {
        keys_line,
        keys: keys.split('\t').map(str::trim).collect(),
        values_line,
        values: values.split('\t').map(str::trim).collect(),
    };
    let rate_hz = fields
        .value("DataRate")?
        .parse::<f64>()
        .ok()
        .filter(|r| r.is_finite() && *r > 0.0);
    let rate_hz = rate_hz.ok_or_else(|| fields.bad_value("DataRate", "a positive frame rate"))?;
    let num_frames = fields.value("NumFrames")?.parse::<usize>();
    let num_frames = num_frames.map_err(|_| fields.bad_value("NumFrames", "a frame count"))?;
    let num_markers = fields.value("NumMarkers")?.parse::<usize>();
    let num_markers = num_markers.map_err(|_| fields.bad_value("NumMarkers", "a marker count"))?;
    let units_text = fields.value("Units")?;
    let units =
        Units::parse(units_text).ok_or_else(|| ReadError::UnknownUnits(units_text.to_owned()))?;
    let start_frame = fields
        .value("OrigDataStartFrame")
        .ok()
        .and_then(super::text::parse_frame_number);

    let (names_line, names) = require(lines, "the `Frame#<tab>Time<tab>` marker-name line")?;
    let labels = parse_names(names_line, &names)?;
    if labels.len() != num_markers {
        return Err(ReadError::MarkerCountMismatch {
            declared: num_markers,
            found: labels.len(),
        });
    }
    let (coords_line, coords) = require(lines, "the `X1<tab>Y1<tab>Z1...` line")?;
    let coordinate_labels = coords.split('\t').filter(|c| !c.trim().is_empty()).count();
    if coordinate_labels != 3 * num_markers {
        return Err(bad_header(
            coords_line,
            "an `X1<tab>Y1<tab>Z1...` line with three labels per marker",
            &coords,
        ));
    }
    Ok(Header {
        rate_hz,
        num_frames,
        units,
        labels,
        start_frame,
    })
}

/// The field-name line and the value line, matched by column.
struct Fields<'a> {
    keys_line: usize,
    keys: Vec<&'a str>,
    values_line: usize,
    values: Vec<&'a str>,
}

impl Fields<'_> {
    /// The value under a field name (case-insensitive).
    fn value(&self, key: &'static str) -> Result<&str, ReadError> {
        let column = self.column(key).ok_or_else(|| ReadError::BadHeader {
            line: self.keys_line,
            expected: "field names including DataRate, NumFrames, NumMarkers and Units",
            found: self.keys.join("\t"),
        })?;
        Ok(self.values.get(column).copied().unwrap_or(""))
    }

    fn column(&self, key: &str) -> Option<usize> {
        self.keys.iter().position(|k| k.eq_ignore_ascii_case(key))
    }

    /// The error for an unparsable value under `key` (which [`Fields::value`] found).
    fn bad_value(&self, key: &'static str, expected: &'static str) -> ReadError {
        let column = self.column(key).unwrap_or(0);
        ReadError::BadCell {
            line: self.values_line,
            column: column + 1,
            field: key.to_owned(),
            expected,
            found: self.values.get(column).copied().unwrap_or("").to_owned(),
        }
    }
}

/// Marker names from `Frame#\tTime\tA\t\t\tB\t\t\t...`: one name every three columns, the two
/// cells after each name empty. Trailing empty cells are tolerated.
fn parse_names(line: usize, text: &str) -> Result<Vec<String>, ReadError> {
    let cells: Vec<&str> = text.split('\t').collect();
    let starts_right = cells.len() >= 2
        && cells[0].trim().eq_ignore_ascii_case("Frame#")
        && cells[1].trim().eq_ignore_ascii_case("Time");
    if !starts_right {
        return Err(bad_header(line, "a line starting `Frame#<tab>Time`", text));
    }
    let mut labels = Vec::new();
    let mut ended = false;
    for chunk in cells[2..].chunks(3) {
        let blank = |c: &&str| c.trim().is_empty();
        if chunk.iter().all(blank) {
            ended = true;
            continue;
        }
        if ended || blank(&chunk[0]) || !chunk[1..].iter().all(blank) {
            return Err(bad_header(
                line,
                "marker names three columns apart, each followed by two empty cells",
                text,
            ));
        }
        labels.push(chunk[0].to_owned());
    }
    Ok(labels)
}

/// The next line, which must exist.
fn require<R: BufRead>(
    lines: &mut Lines<R>,
    expected: &'static str,
) -> Result<(usize, String), ReadError> {
    let line = lines.next_number();
    match lines.next_line()? {
        Some((n, text)) => Ok((n, text.to_owned())),
        None => Err(ReadError::UnexpectedEnd { line, expected }),
    }
}

fn bad_header(line: usize, expected: &'static str, found: &str) -> ReadError {
    ReadError::BadHeader {
        line,
        expected,
        found: found.to_owned(),
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // a failed unwrap is a failed test
mod tests;
