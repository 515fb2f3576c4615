//! The shortest decimal text of an `f32`, as std's `Display` (`{}`) writes it, byte for byte,
//! at several times its speed: zmij finds the digits (the shortest that read back to the same
//! `f32`, the closest to it among those, as std's Grisu and Dragon find), and they are laid out
//! here as std lays them out: no exponent, no trailing `.0`, `-0` for negative zero.
//!
//! `project`'s CSV writes twenty of these per frame, and std's formatting was a third of its
//! time (issue 35). The identity with std is checked over every `f32` bit pattern by
//! `cargo run --release -p replay --example shortest_f32`, and over samples by this module's
//! tests.

/// Appends `value` to `out` exactly as `write!(out, "{value}")` would.
pub fn push_f32(out: &mut String, value: f32) {
    let mut buffer = zmij::Buffer::new();
    if !value.is_finite() {
        // "NaN", "inf", "-inf", as std writes them.
        out.push_str(buffer.format(value));
        return;
    }
    let text = buffer.format_finite(value);
    if let Some(exact) = exact_digits(value) {
        if exact == Layout::of(text).digits.len() as i32 + 1 {
            // Halfway between two shortest candidates: zmij rounds the tie to even, std does
            // not always; std decides these few.
            use std::fmt::Write as _;
            write!(out, "{value}").expect("writing to a String cannot fail");
            return;
        }
    }
    if !text.contains('e') {
        // Positional already (`0.00123`, `12.5`, `1200.0`): std writes it without `.0`.
        out.push_str(text.strip_suffix(".0").unwrap_or(text));
        return;
    }
    Layout::of(text).push(out);
}

/// A zmij text taken apart: sign, significant digits, and where the decimal point falls.
struct Layout<'a> {
    negative: bool,
    digits: Digits<'a>,
    /// The point's place, in digits from the first significant one (may be negative or past
    /// the last).
    point: i32,
}

impl<'a> Layout<'a> {
    fn of(text: &'a str) -> Layout<'a> {
        let (negative, text) = match text.strip_prefix('-') {
            Some(rest) => (true, rest),
            None => (false, text),
        };
        let (mantissa, exponent) = match text.split_once('e') {
            Some((m, e)) => (m, e.parse::<i32>().expect("zmij writes a decimal exponent")),
            None => (text, 0),
        };
        let (whole, fraction) = mantissa.split_once('.').unwrap_or((mantissa, ""));
        // The significant digits are `whole` then `fraction` without the zeros at either end.
        let mut point = whole.len() as i32 + exponent;
        let whole_digits = whole.trim_start_matches('0');
        point -= (whole.len() - whole_digits.len()) as i32;
        let fraction = if whole_digits.is_empty() {
            let trimmed = fraction.trim_start_matches('0');
            point -= (fraction.len() - trimmed.len()) as i32;
            trimmed
        } else {
            fraction
        };
        let fraction = fraction.trim_end_matches('0');
        let digits = if fraction.is_empty() {
            // `1200.0`: the digits are `12`.
            Digits(whole_digits.trim_end_matches('0'), "")
        } else {
            Digits(whole_digits, fraction)
        };
        Layout {
            negative,
            digits,
            point,
        }
    }

    /// Appends the number as std lays it out.
    fn push(&self, out: &mut String) {
        let (digits, point) = (&self.digits, self.point);
        if self.negative {
            out.push('-');
        }
        let count = digits.len() as i32;
        if count == 0 {
            out.push('0');
        } else if point <= 0 {
            out.push_str("0.");
            push_zeros(out, -point);
            digits.push_range(out, 0, count);
        } else if point >= count {
            digits.push_range(out, 0, count);
            push_zeros(out, point - count);
        } else {
            digits.push_range(out, 0, point);
            out.push('.');
            digits.push_range(out, point, count);
        }
    }
}

/// How many significant digits `value`'s exact decimal expansion has, when that can be one more
/// than its shortest text's (a tie between two shortest candidates is then possible); `None`
/// when it cannot.
///
/// A finite `f32` is `m · 2^e`. With `e ≥ 0` it is an integer: below 2^24 its shortest text
/// is exact, above it every candidate ending in 5 is odd while the value is a multiple of
/// 2^e, so no tie. Otherwise it is `(m / 2^t) · 5^k / 10^k` (`t` the trailing zero bits of
/// `m`, `k = -e - t`): that odd numerator has over 10 digits once `k > 14`, more than one
/// past the 9 a shortest `f32` needs.
fn exact_digits(value: f32) -> Option<i32> {
    let bits = value.to_bits();
    let (biased, fraction) = ((bits >> 23) & 0xff, bits & 0x7f_ffff);
    let (m, e) = match biased {
        0 => (fraction, -149),
        _ => (fraction | 0x80_0000, biased as i32 - 150),
    };
    if m == 0 || e >= 0 {
        return None;
    }
    let t = m.trailing_zeros() as i32;
    let k = -e - t;
    if !(1..=14).contains(&k) {
        return None;
    }
    let numerator = u64::from(m >> t) * 5u64.pow(k as u32);
    Some(numerator.ilog10() as i32 + 1)
}

/// Significant digits held as two slices of the formatted text (either side of its point).
#[derive(Clone, Copy)]
struct Digits<'a>(&'a str, &'a str);

impl Digits<'_> {
    fn len(&self) -> usize {
        self.0.len() + self.1.len()
    }

    /// Appends digits `from..to` (indices into the whole digit string).
    fn push_range(&self, out: &mut String, from: i32, to: i32) {
        let (from, to) = (from as usize, to as usize);
        let split = self.0.len();
        if from < split {
            out.push_str(&self.0[from..to.min(split)]);
        }
        if to > split {
            out.push_str(&self.1[from.max(split) - split..to - split]);
        }
    }
}

fn push_zeros(out: &mut String, count: i32) {
    for _ in 0..count {
        out.push('0');
    }
}

mod read;

pub(crate) use read::parse_plain;

#[cfg(test)]
mod tests;
