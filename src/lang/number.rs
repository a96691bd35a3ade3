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

/// Most digits a literal may have for the fast path: 19 decimal digits always fit a `u64`
/// (10^19 < 2^64), so the mantissa folded from them cannot wrap.
const FAST_DIGITS: usize = 19;

/// The digits at the start of `s` folded into `acc` (wrapping past [`FAST_DIGITS`], where
/// the caller no longer uses it), and how many there were.
#[inline(always)]
fn digits(s: &[u8], mut acc: u64) -> (u64, usize) {
    let mut k = 0;
    while let Some(&c) = s.get(k) {
        let d = c.wrapping_sub(b'0');
        if d > 9 {
            break;
        }
        acc = acc.wrapping_mul(10).wrapping_add(u64::from(d));
        k += 1;
    }
    (acc, k)
}

/// Scan an unsigned literal at the start of `s`: digits with at most one `.`, at least one
/// digit. Returns the value and the number of bytes used, or `None` if `s` does not start
/// with a literal.
///
/// One pass of one subtraction and one compare a digit (callgrind: the former per-digit
/// count of significant digits cost about twice the instructions); a literal of more than
/// [`FAST_DIGITS`] digits takes the standard library's path, which rounds the same.
#[inline]
pub(crate) fn scan_unsigned(s: &[u8]) -> Option<(f64, usize)> {
    let (mantissa, int_digits) = digits(s, 0);
    let mut i = int_digits;
    let (mantissa, frac_digits) = if s.get(i) == Some(&b'.') {
        i += 1;
        let (m, k) = digits(&s[i..], mantissa);
        i += k;
        (m, k)
    } else {
        (mantissa, 0)
    };
    if int_digits + frac_digits == 0 {
        return None;
    }
    if int_digits + frac_digits <= FAST_DIGITS
        && mantissa < (1u64 << 53)
        && frac_digits < POW10.len()
    {
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
            "0.0000000000000000000001",
            "0000000000000000000000012.5",
            "9999999999999999999",
            "18446744073709551616",
            "123456789012345678.9",
            "1.0000000000000000000",
        ] {
            let (v, n) = scan(s).unwrap();
            assert_eq!(n, s.len(), "{s}");
            assert_eq!(v, s.parse::<f64>().unwrap(), "{s}");
        }
    }

    proptest::proptest! {
        /// Any digits-and-dot text, any length, any bytes after it: the standard library's
        /// value and the literal's length.
        #[test]
        fn any_literal_converts_like_the_standard_library(
            int in "[0-9]{0,30}",
            frac in proptest::option::of("[0-9]{0,30}"),
            tail in "[ XA;(\\-/:é]{0,3}",
        ) {
            let lit = match &frac {
                Some(f) => format!("{int}.{f}"),
                None => int.clone(),
            };
            let text = format!("{lit}{tail}");
            let got = scan(&text);
            if int.is_empty() && frac.as_deref().unwrap_or("").is_empty() {
                proptest::prop_assert_eq!(got, None);
            } else {
                let want: f64 = lit.parse().unwrap();
                proptest::prop_assert_eq!(got, Some((want, lit.len())));
            }
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
