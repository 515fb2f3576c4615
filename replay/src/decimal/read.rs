//! Plain decimals read as std reads them, without std's general parser: the TRC and CSV
//! readers' samples are almost all of this form (`-12.345678`), and std's `f64::from_str`
//! (finding the number's parts, then Eisel-Lemire) was most of the time reading them took
//! after the cells were split (perf of `train` on the AnimFace TRC takes: 15 % of its CPU).
//!
//! A decimal of at most 19 significant digits, none after the 22nd past the point, whose
//! digits read as an integer `m ≤ 2^53`, is `m / 10^k` with both operands exact in `f64`: one
//! IEEE division rounds it correctly, which is what std returns (Clinger's fast path). Any
//! other text goes to std. `tests` checks the two agree, bit for bit, on generated decimals
//! and on the edges.

/// Powers of ten exact in `f64`.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// `text.parse::<f64>()` for a plain decimal: an optional sign, digits with at most one point
/// among or around them, at most 19 from the first nonzero one, at most 22 after the point,
/// their integer at most 2^53. `None` for any other text (an exponent, `NaN`, spaces, more
/// digits): the caller asks std.
pub(crate) fn parse_plain(text: &str) -> Option<f64> {
    let bytes = text.as_bytes();
    let (negative, digits) = match bytes.first()? {
        b'-' => (true, &bytes[1..]),
        b'+' => (false, &bytes[1..]),
        _ => (false, bytes),
    };
    let mut mantissa: u64 = 0;
    // Digits from the first nonzero one (leading zeros add nothing), and whether any digit was.
    let (mut significant, mut any) = (0, false);
    let mut point = None;
    for (i, &b) in digits.iter().enumerate() {
        match b {
            b'0'..=b'9' if significant < 19 => {
                mantissa = mantissa * 10 + u64::from(b - b'0');
                significant += usize::from(mantissa != 0);
                any = true;
            }
            b'.' if point.is_none() => point = Some(i),
            _ => return None,
        }
    }
    let scale = point.map_or(0, |at| digits.len() - at - 1);
    if !any || mantissa > 1 << 53 || scale >= POW10.len() {
        return None;
    }
    let value = mantissa as f64 / POW10[scale];
    Some(if negative { -value } else { value })
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::parse_plain;

    /// Ours where the fast path takes the text, std's anyway; and whether it took it.
    fn both(text: &str) -> (Option<u64>, Option<u64>, bool) {
        let std = text.parse::<f64>().ok().map(f64::to_bits);
        let ours = parse_plain(text);
        (
            ours.or(std.map(f64::from_bits)).map(f64::to_bits),
            std,
            ours.is_some(),
        )
    }

    #[test]
    fn edges_read_as_std_reads_them_or_go_to_std() {
        let taken = [
            "0",
            "-0",
            "+0",
            "0.0",
            "-0.0",
            "5.",
            ".5",
            "-.5",
            "+.5",
            "1",
            "12.345678",
            "-1234.5678",
            "9007199254740992",
            "0.1",
            "0.3",
            "123456.123456789",
            "0.0000000000000000000001",
            "1.797693134862315",
        ];
        for text in taken {
            let (ours, std, fast) = both(text);
            assert!(fast, "{text} takes the fast path");
            assert_eq!(ours, std, "{text}");
        }
        let to_std = [
            "",
            ".",
            "-",
            "+",
            "1e5",
            "1E5",
            "NaN",
            "nan",
            "inf",
            "-inf",
            " 1",
            "1 ",
            "1.2.3",
            "--1",
            "0x10",
            "9007199254740993",
            "12345678901234567890",
            "1,5",
            "0.00000000000000000000001",
            "١",
            "123456789.123456789",
            "1.7976931348623157",
        ];
        for text in to_std {
            assert!(parse_plain(text).is_none(), "{text} goes to std");
        }
    }

    proptest! {
        #[test]
        fn plain_decimals_read_as_std_reads_them(
            negative in any::<bool>(),
            whole in "[0-9]{0,12}",
            fraction in proptest::option::of("[0-9]{0,12}"),
        ) {
            let sign = if negative { "-" } else { "" };
            let text = match &fraction {
                Some(f) => format!("{sign}{whole}.{f}"),
                None => format!("{sign}{whole}"),
            };
            let (ours, std, _) = both(&text);
            prop_assert_eq!(ours, std, "{}", text);
        }

        #[test]
        fn any_f64_written_by_std_reads_back_the_same(bits in any::<u64>()) {
            let value = f64::from_bits(bits);
            let text = format!("{value}");
            let (ours, std, _) = both(&text);
            prop_assert_eq!(ours, std, "{}", text);
        }
    }
}
