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

/// Digits [`digit_run`] reads at once: the bytes of a `u64`.
pub(crate) const RUN: usize = 8;

/// Exact powers of ten in a `u64`, to place a fraction's digits after the integer's.
const POW10_U64: [u64; RUN] = [1, 10, 100, 1_000, 10_000, 100_000, 1_000_000, 10_000_000];

/// The first eight bytes of `s` as a little-endian word; past the end of a shorter `s`, zero
/// bytes (not digits).
#[inline(always)]
fn load_word(s: &[u8]) -> u64 {
    match s.first_chunk::<RUN>() {
        Some(w) => u64::from_le_bytes(*w),
        // Shifted in byte by byte: a copy into a buffer would be a memcpy call.
        None => s.iter().rev().fold(0u64, |w, &c| (w << 8) | u64::from(c)),
    }
}

/// The ASCII digits at the start of `s`, up to [`RUN`] of them: how many, and their value.
/// A count of [`RUN`] means more digits may follow; below it, the run ends there.
///
/// Eight bytes a step in a `u64` ("SWAR"): which bytes are digits, then the value of the
/// leading ones by three multiplications (callgrind: a byte-at-a-time loop cost about 90
/// instructions for a literal such as `-6.789`).
#[inline(always)]
pub(crate) fn digit_run(s: &[u8]) -> (u64, usize) {
    const ZEROS: u64 = 0x3030_3030_3030_3030;
    const HIGHS: u64 = 0x8080_8080_8080_8080;
    // Byte k of `d` is its digit's value while bytes 0..=k are digits: a byte below '0' sets
    // its high bit (and may borrow from the next byte, past the run), one above '9' sets
    // the high bit of itself + 0x76 (and may carry into the next one, past the run).
    let d = load_word(s).wrapping_sub(ZEROS);
    let not_digit = (d | d.wrapping_add(0x7676_7676_7676_7676)) & HIGHS;
    let n = (not_digit.trailing_zeros() / 8) as usize;
    if n == 0 {
        return (0, 0);
    }
    // The run's digits at the top of the word, zero digits below them: the first digit
    // (lowest byte) is the most significant, as in an eight-digit number with leading zeros.
    let v = d << (8 * (RUN - n));
    // Pairs, then fours, then all eight digits (each step's products fit their lanes).
    let v = v.wrapping_mul(10).wrapping_add(v >> 8);
    const LANES: u64 = 0x0000_00FF_0000_00FF;
    const MUL1: u64 = 100 + (1_000_000 << 32);
    const MUL2: u64 = 1 + (10_000 << 32);
    let v = (v & LANES)
        .wrapping_mul(MUL1)
        .wrapping_add(((v >> 16) & LANES).wrapping_mul(MUL2))
        >> 32;
    (v, n)
}

/// Scan an unsigned literal at the start of `s`: digits with at most one `.`, at least one
/// digit. Returns the value and the number of bytes used, or `None` if `s` does not start
/// with a literal.
///
/// Up to seven integer and seven fraction digits, the common literal, are read by
/// [`digit_run`]; their mantissa (below 10^14) is exact in an `f64`, so it is converted as
/// by [`scan_long`], which takes every longer literal.
#[inline(always)]
pub(crate) fn scan_unsigned(s: &[u8]) -> Option<(f64, usize)> {
    let (int, int_digits) = digit_run(s);
    if int_digits == RUN {
        return scan_long(s);
    }
    let (mantissa, frac_digits, len) = if s.get(int_digits) == Some(&b'.') {
        let (frac, frac_digits) = digit_run(s.get(int_digits + 1..).unwrap_or(&[]));
        if frac_digits == RUN {
            return scan_long(s);
        }
        (
            int * POW10_U64[frac_digits] + frac,
            frac_digits,
            int_digits + 1 + frac_digits,
        )
    } else {
        (int, 0, int_digits)
    };
    if int_digits + frac_digits == 0 {
        return None;
    }
    Some((mantissa as f64 / POW10[frac_digits], len))
}

/// [`scan_unsigned`] one digit at a time, for literals of eight digits or more on either
/// side of the point.
///
/// One pass of one subtraction and one compare a digit (callgrind: the former per-digit
/// count of significant digits cost about twice the instructions); a literal of more than
/// [`FAST_DIGITS`] digits takes the standard library's path, which rounds the same.
#[inline(never)]
fn scan_long(s: &[u8]) -> Option<(f64, usize)> {
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

    /// Every split of up to nine integer and nine fraction digits, with the bytes next to
    /// the digits ('/', ':', NUL, high bytes …) after them and at every place of the word:
    /// the word-at-a-time path gives the one-digit-at-a-time path's value and length, which
    /// is the standard library's.
    #[test]
    fn word_at_a_time_reads_like_digit_at_a_time() {
        let mut seed: u64 = 0x9E37_79B9_7F4A_7C15;
        let mut digit = move || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            b'0' + ((seed >> 33) % 10) as u8
        };
        let tails: [&[u8]; 9] = [
            b"", b" X1", b"/", b":", b"\0", b"\xff", b"\x8a9", b"..5", b"E5",
        ];
        let mut checked = 0;
        for int_len in 0..=9 {
            for frac_len in [
                None,
                Some(0),
                Some(1),
                Some(2),
                Some(3),
                Some(6),
                Some(7),
                Some(8),
                Some(9),
            ] {
                // After digits without a point, a tail's point would continue the literal.
                for tail in tails
                    .iter()
                    .filter(|t| frac_len.is_some() || t[..] != *b"..5")
                {
                    for _ in 0..20 {
                        let mut lit: Vec<u8> = (0..int_len).map(|_| digit()).collect();
                        if let Some(f) = frac_len {
                            lit.push(b'.');
                            lit.extend((0..f).map(|_| digit()));
                        }
                        let mut text = lit.clone();
                        text.extend_from_slice(tail);
                        let got = scan_unsigned(&text);
                        assert_eq!(got, scan_long(&text), "{text:?}");
                        let as_str = std::str::from_utf8(&lit).unwrap_or("");
                        let want = as_str.parse::<f64>().ok().map(|v| (v, lit.len()));
                        assert_eq!(got, want, "{text:?}");
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 10_000);
    }

    #[test]
    fn a_digit_run_counts_and_values_up_to_eight_digits() {
        assert_eq!(digit_run(b""), (0, 0));
        assert_eq!(digit_run(b"X"), (0, 0));
        assert_eq!(digit_run(b"0"), (0, 1));
        assert_eq!(digit_run(b"12.5"), (12, 2));
        assert_eq!(digit_run(b"1234567"), (1_234_567, 7));
        assert_eq!(digit_run(b"12345678"), (12_345_678, RUN));
        assert_eq!(digit_run(b"99999999999"), (99_999_999, RUN));
        assert_eq!(digit_run(b"0000012/"), (12, 7));
        for b in (0..=255u8).filter(|b| !b.is_ascii_digit()) {
            assert_eq!(digit_run(&[b'7', b, b'1']), (7, 1), "{b}");
            assert_eq!(digit_run(&[b, b'1']), (0, 0), "{b}");
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
