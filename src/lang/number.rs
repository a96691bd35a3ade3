//! NC number literals: `12`, `-6.789`, `.5`, `12.` — scanned byte by byte, converted exactly.
//!
//! No exponent: `E` is an address letter, so `X1E5` is `X1` followed by `E5`. The common
//! short literal is converted with Clinger's fast path (an exact integer mantissa divided by
//! an exact power of ten is correctly rounded), anything longer by the standard library; both
//! give the same, correctly rounded `f64`.

/// Why a literal beyond the largest `f64` (more than 308 digits before the point) is
/// refused: it would read as infinity, which no word may carry and the canonical text
/// cannot print back. Error 20200 at the literal.
pub(crate) const TOO_LARGE: &str = "number too large (beyond 1.8e308)";

/// Exact powers of ten representable in an `f64`.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Scan an unsigned literal at the start of `s`: digits with at most one `.`, at least one
/// digit. Returns the value and the number of bytes used, or `None` if `s` does not start
/// with a literal.
#[inline]
pub(crate) fn scan_unsigned(s: &[u8]) -> Option<(f64, usize)> {
    let mut i = 0;
    let mut mantissa: u64 = 0;
    let mut digits = 0usize; // significant digits folded into `mantissa`
    let mut frac_digits = 0usize;
    let mut any_digit = false;
    let mut exact = true;
    while i < s.len() && s[i].is_ascii_digit() {
        any_digit = true;
        if digits < 19 {
            mantissa = mantissa * 10 + u64::from(s[i] - b'0');
            if mantissa != 0 {
                digits += 1;
            }
        } else {
            exact = false;
        }
        i += 1;
    }
    if i < s.len() && s[i] == b'.' {
        i += 1;
        while i < s.len() && s[i].is_ascii_digit() {
            any_digit = true;
            if digits < 19 {
                mantissa = mantissa * 10 + u64::from(s[i] - b'0');
                if mantissa != 0 {
                    digits += 1;
                }
                frac_digits += 1;
            } else {
                exact = false;
            }
            i += 1;
        }
    }
    if !any_digit {
        return None;
    }
    if exact && mantissa < (1u64 << 53) && frac_digits < POW10.len() {
        return Some((mantissa as f64 / POW10[frac_digits], i));
    }
    // Slow path: long literals. The scanned bytes are ASCII digits and one dot, so they are
    // valid UTF-8 and a valid Rust float (after a leading "0" for ".5"-style literals, which
    // `str::parse` accepts anyway).
    let text = std::str::from_utf8(&s[..i]).ok()?;
    let v: f64 = text.parse().ok()?;
    // More than 308 integer digits: beyond f64, and no machine value. Not a literal (the
    // callers refuse it as 20200) rather than an infinity every later step must guard.
    v.is_finite().then_some((v, i))
}

/// What a refused literal may have run into, for the messages that refuse it.
pub(crate) const LITERAL_LIMIT: &str = "a number has at most 308 integer digits";

#[cfg(test)]
mod tests {
    use super::*;

    fn scan(s: &str) -> Option<(f64, usize)> {
        scan_unsigned(s.as_bytes())
    }

    #[test]
    fn literals_convert_like_the_standard_library() {
        for s in [
            "0",
            "12",
            "12.",
            ".5",
            "12.345",
            "6.789",
            "0.1",
            "3000",
            "0.000001",
            "123456789.123",
            "9007199254740993",
            "1234567890123456789012",
            "0.30000000000000004",
            "17.021",
            "99999999999999999999.5",
        ] {
            let (v, n) = scan(s).unwrap();
            assert_eq!(n, s.len(), "{s}");
            assert_eq!(v, s.parse::<f64>().unwrap(), "{s}");
        }
    }

    #[test]
    fn stops_at_the_first_non_number_byte() {
        assert_eq!(scan("1.5Y2"), Some((1.5, 3)));
        assert_eq!(scan("1E5"), Some((1.0, 1)));
        assert_eq!(scan("1.2.3"), Some((1.2, 3)));
        assert_eq!(scan("."), None);
        assert_eq!(scan("X"), None);
        assert_eq!(scan(""), None);
    }
}
