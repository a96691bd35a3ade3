//! The axes: their letters, how many, and a position over all of them. The parser, the
//! parameter lists, the decoder, motion and the report all index axes the same way.

/// Axes the emulator knows, in this order. Configured axes are a subset.
pub const AXIS_LETTERS: [u8; MAX_AXES] = *b"XYZABC";
pub const MAX_AXES: usize = 6;

/// Axis positions: mm for linear axes X Y Z, degrees for rotary axes A B C.
pub type Position = [f64; MAX_AXES];
