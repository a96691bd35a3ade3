//! Byte searches sized for NC lines. A line is a few dozen bytes: eight bytes per step in a
//! `u64` ("SWAR") answers there with less set-up than a SIMD search (callgrind: memchr's
//! dispatch cost about 70 instructions a call on such lines).

const ONES: u64 = 0x0101_0101_0101_0101;
const HIGHS: u64 = 0x8080_8080_8080_8080;

/// A word with a high bit in each byte of `w` that equals `x` (exact for the first such
/// byte, which is all a yes/no answer needs).
#[inline]
pub(crate) fn equal_bytes(w: u64, x: u8) -> u64 {
    let v = w ^ (ONES * u64::from(x));
    v.wrapping_sub(ONES) & !v & HIGHS
}

/// The line as `u64` words, eight bytes each; the last word overlaps the one before it
/// (or, for a line under eight bytes, is padded with zero bytes), so there is no byte-wise
/// tail. Zero padding is harmless to every search here: none looks for a zero byte.
#[inline]
fn fold_words<T>(b: &[u8], init: T, mut f: impl FnMut(T, u64) -> T) -> T {
    if b.len() < 8 {
        // Shifted in byte by byte: a copy into a buffer would be a memcpy call.
        let w = b.iter().rev().fold(0u64, |w, &c| (w << 8) | u64::from(c));
        return f(init, w);
    }
    let (words, rest) = b.as_chunks::<8>();
    let mut acc = words
        .iter()
        .fold(init, |acc, w| f(acc, u64::from_le_bytes(*w)));
    if !rest.is_empty() {
        let mut last = [0u8; 8];
        last.copy_from_slice(&b[b.len() - 8..]);
        acc = f(acc, u64::from_le_bytes(last));
    }
    acc
}

/// Does `b` hold the byte `x` (not zero)?
#[inline]
pub(crate) fn has_byte(b: &[u8], x: u8) -> bool {
    fold_words(b, 0, |acc, w| acc | equal_bytes(w, x)) != 0
}

/// Is `b` ASCII, and does it hold a CR or LF? One pass for both.
#[inline]
pub(crate) fn ascii_and_line_end(b: &[u8]) -> (bool, bool) {
    let (or, ends) = fold_words(b, (0u64, 0u64), |(or, ends), w| {
        (or | w, ends | equal_bytes(w, b'\r') | equal_bytes(w, b'\n'))
    });
    (or & HIGHS == 0, ends != 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_a_byte_at_every_place_and_no_false_one() {
        assert_eq!(ascii_and_line_end(b""), (true, false));
        assert!(!has_byte(b"", b'\\'));
        for len in 1..40 {
            let clean = vec![b'X'; len];
            assert!(!has_byte(&clean, b'\\'));
            assert_eq!(ascii_and_line_end(&clean), (true, false));
            for at in 0..len {
                let mut b = clean.clone();
                b[at] = b'\\';
                assert!(has_byte(&b, b'\\'), "{len} {at}");
                b[at] = b'\n';
                assert_eq!(ascii_and_line_end(&b), (true, true), "{len} {at}");
                b[at] = b'\r';
                assert_eq!(ascii_and_line_end(&b), (true, true), "{len} {at}");
                // Bytes next to the ones searched for, and bytes with the high bit, are no match.
                for near in [0x5b, 0x5d, 0x0b, 0x0c, 0xdc, 0x8a, 0x8d] {
                    b[at] = near;
                    assert!(!has_byte(&b, b'\\'), "{len} {at} {near}");
                    assert_eq!(
                        ascii_and_line_end(&b),
                        (near < 0x80, false),
                        "{len} {at} {near}"
                    );
                }
            }
        }
    }
}
