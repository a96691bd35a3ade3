//! The axes: their letters, how many, and a position over all of them. The parser, the
//! parameter lists, the decoder, motion and the report all index axes the same way.

/// Axes the emulator knows, in this order. Configured axes are a subset.
pub const AXIS_LETTERS: [u8; MAX_AXES] = *b"XYZABC";
pub const MAX_AXES: usize = 6;

/// Axis positions: mm for linear axes X Y Z, degrees for rotary axes A B C.
pub type Position = [f64; MAX_AXES];

/// The slot of an axis letter (upper case), `X` 0 … `C` 5: asked for every axis word of every
/// block, so a jump table rather than a search of [`AXIS_LETTERS`].
#[inline]
pub(crate) fn slot_of(letter: u8) -> Option<usize> {
    match letter {
        b'X' => Some(0),
        b'Y' => Some(1),
        b'Z' => Some(2),
        b'A' => Some(3),
        b'B' => Some(4),
        b'C' => Some(5),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slot_of_agrees_with_the_letters() {
        for (i, &l) in AXIS_LETTERS.iter().enumerate() {
            assert_eq!(slot_of(l), Some(i));
        }
        assert_eq!(slot_of(b'U'), None);
    }
}
