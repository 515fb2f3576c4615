//! A minimal, bounds-checked parser of the C3D parameter section: enough to locate and label the
//! 3D points when c3dio refuses a file, and to validate what c3dio returns.

use super::binary::{take2, take4, Processor, BLOCK};
use crate::error::c3d::C3dError;

/// The value of one parameter.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// Characters: `dims[0]` is the string width, the remaining dimensions count strings.
    Char(Vec<u8>),
    /// Unsigned bytes.
    Byte(Vec<u8>),
    /// 16-bit integers.
    Int(Vec<i16>),
    /// 32-bit floats.
    Float(Vec<f32>),
}

/// One parameter: `GROUP:NAME`, its dimensions and value.
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    /// Group name, upper case.
    pub group: String,
    /// Parameter name, upper case.
    pub name: String,
    /// Dimensions as stored (empty for a scalar).
    pub dims: Vec<usize>,
    /// The data.
    pub value: Value,
    /// Absolute byte offset of the data in the file, where a repair patches a count in place.
    pub offset: usize,
}

/// All parameters of a file, in file order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Params {
    /// The parameters.
    pub list: Vec<Param>,
}

impl Params {
    /// The parameter `group:name` (case-insensitive), if present.
    pub fn get(&self, group: &str, name: &str) -> Option<&Param> {
        self.list
            .iter()
            .find(|p| p.group.eq_ignore_ascii_case(group) && p.name.eq_ignore_ascii_case(name))
    }

    /// The first number of a numeric parameter, as f64 (integers read as unsigned 16-bit when
    /// `unsigned`, since counts and frame numbers are stored in signed words but never negative).
    pub fn number(&self, group: &str, name: &str, unsigned: bool) -> Option<f64> {
        self.numbers(group, name, unsigned)?.first().copied()
    }

    /// All numbers of a numeric parameter, as f64.
    pub fn numbers(&self, group: &str, name: &str, unsigned: bool) -> Option<Vec<f64>> {
        match &self.get(group, name)?.value {
            Value::Int(v) if unsigned => Some(v.iter().map(|&x| f64::from(x as u16)).collect()),
            Value::Int(v) => Some(v.iter().map(|&x| f64::from(x)).collect()),
            Value::Float(v) => Some(v.iter().map(|&x| f64::from(x)).collect()),
            Value::Byte(v) => Some(v.iter().map(|&x| f64::from(x)).collect()),
            Value::Char(_) => None,
        }
    }

    /// A character parameter split into its strings, trailing blanks and NULs trimmed.
    pub fn strings(&self, group: &str, name: &str) -> Option<Vec<String>> {
        let p = self.get(group, name)?;
        let Value::Char(bytes) = &p.value else {
            return None;
        };
        let width = p.dims.first().copied().unwrap_or(bytes.len());
        if width == 0 {
            return Some(Vec::new());
        }
        Some(
            bytes
                .chunks(width)
                .map(|c| {
                    String::from_utf8_lossy(c)
                        .trim_end_matches(['\0', ' '])
                        .trim()
                        .to_string()
                })
                .collect(),
        )
    }
}

/// Parses the parameter section that starts at 1-based block `block` (the header's data block
/// bounds it). An empty section (no groups) gives no parameters.
///
/// # Errors
/// [`C3dError::BadParameters`] naming the byte offset when an entry runs past the file or has an
/// unknown data type.
pub fn parse(
    bytes: &[u8],
    block: usize,
    data_block: usize,
    p: Processor,
) -> Result<Params, C3dError> {
    let start = (block - 1) * BLOCK;
    // The section runs to the data when the data follows it (its own block count is sometimes
    // too small), else as far as that count says; a record whose "next" offset leaves the
    // section marks the end, as some writers leave junk in the last one.
    let end = if data_block > block {
        (data_block - 1) * BLOCK
    } else {
        let declared = bytes.get(start + 2).map_or(1, |&b| usize::from(b).max(1));
        start.saturating_add(declared * BLOCK)
    };
    let end = end.min(bytes.len());
    let section = bytes.get(start..end).unwrap_or(&[]);
    let mut groups: Vec<(i8, String)> = Vec::new();
    let mut raw: Vec<(i8, Param)> = Vec::new();
    let mut at = 4;
    while let Some(entry) =
        Entry::parse(section, at, p).map_err(|reason| C3dError::BadParameters {
            offset: start + at,
            reason,
        })?
    {
        match entry.kind {
            Kind::Group => groups.push((entry.id.saturating_abs(), entry.name)),
            Kind::Param(dims, value, data_at) => raw.push((
                entry.id,
                Param {
                    group: String::new(),
                    name: entry.name,
                    dims,
                    value,
                    offset: start + data_at,
                },
            )),
        }
        match entry.next {
            Some(next) => at = next,
            None => break,
        }
    }
    let list = raw
        .into_iter()
        .map(|(id, mut param)| {
            param.group = groups
                .iter()
                .find(|(g, _)| *g == id)
                .map_or_else(|| format!("GROUP{id}"), |(_, n)| n.clone());
            param
        })
        .collect();
    Ok(Params { list })
}

enum Kind {
    Group,
    /// Dimensions, value and the data's offset in the section.
    Param(Vec<usize>, Value, usize),
}

struct Entry {
    id: i8,
    name: String,
    kind: Kind,
    next: Option<usize>,
}

impl Entry {
    /// One group or parameter record at `at`; `None` at the terminating record.
    fn parse(s: &[u8], at: usize, p: Processor) -> Result<Option<Entry>, &'static str> {
        let (Some(&len), Some(&id)) = (s.get(at), s.get(at + 1)) else {
            return Ok(None);
        };
        let (len, id) = (usize::from((len as i8).unsigned_abs()), id as i8);
        if len == 0 || id == 0 {
            return Ok(None);
        }
        let name_end = at + 2 + len;
        let name = s.get(at + 2..name_end).ok_or("name runs past the end")?;
        let name = String::from_utf8_lossy(name).to_ascii_uppercase();
        let offset = take2(s, name_end).ok_or("offset runs past the end")?;
        let offset = usize::from(p.u16(offset));
        // An offset of zero marks the last record.
        let next = (offset != 0).then_some(name_end + offset);
        if next.is_some_and(|n| n <= at) {
            return Err("offset points backwards");
        }
        let next = next.filter(|&n| n + 1 < s.len());
        let kind = if id < 0 {
            Kind::Group
        } else {
            let (dims, value, data_at) = parse_value(s, name_end + 2, p)?;
            Kind::Param(dims, value, data_at)
        };
        Ok(Some(Entry {
            id,
            name,
            kind,
            next,
        }))
    }
}

/// A parameter's dimensions, value and where its data starts in `s`.
fn parse_value(
    s: &[u8],
    at: usize,
    p: Processor,
) -> Result<(Vec<usize>, Value, usize), &'static str> {
    let ty = *s.get(at).ok_or("type runs past the end")? as i8;
    let ndims = usize::from(*s.get(at + 1).ok_or("dimensions run past the end")?);
    let dims: Vec<usize> = s
        .get(at + 2..at + 2 + ndims)
        .ok_or("dimensions run past the end")?
        .iter()
        .map(|&d| usize::from(d))
        .collect();
    let count = dims
        .iter()
        .try_fold(1usize, |a, &d| a.checked_mul(d))
        .ok_or("dimensions overflow")?;
    let size = match ty {
        -1 | 1 => 1,
        2 => 2,
        4 => 4,
        _ => return Err("unknown data type"),
    };
    let data_at = at + 2 + ndims;
    let data = s
        .get(data_at..data_at + count.saturating_mul(size).min(s.len()))
        .ok_or("data runs past the end")?;
    let value = match ty {
        -1 => Value::Char(data.to_vec()),
        1 => Value::Byte(data.to_vec()),
        2 => Value::Int(
            (0..count)
                .filter_map(|i| take2(data, i * 2).map(|b| p.i16(b)))
                .collect(),
        ),
        _ => Value::Float(
            (0..count)
                .filter_map(|i| take4(data, i * 4).map(|b| p.f32(b)))
                .collect(),
        ),
    };
    Ok((dims, value, data_at))
}
