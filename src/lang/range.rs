//! Value ranges of ordinary words: the one validation the parser applies to literal words
//! and the decoder to evaluated ones, so `ncchannel check` and a run refuse the same values
//! with the same numbers.
//!
//! G, M and H are codes the parser reads itself; every other word takes a finite value
//! (literals beyond `f64` are refused while scanning, expressions by the evaluator), and:
//!
//! | word | range | refused with |
//! |---|---|---|
//! | F | not negative | 20176 (the kernel's "negative or zero F"; F0 is [`super::codes::NO_FEED`] in a feed move) |
//! | S | not negative | 900132 |
//! | T, D | a whole number 0 to 4294967295 | 900132 |
//! | I, J, K | within ±214,748.3647 | 20020 (TF5200: circle centre parameter outside the data format) |
//! | R | within ±214,748.3647 | 20054 (TF5200: centre outside the data format, example `R1000000`) |
//!
//! Axis words are bounded where the machine is known: by the software limits of
//! runtime.toml, which the decoder checks for every end point (21897).

use super::codes::{ARC_CENTER_RANGE, ARC_RADIUS_RANGE, BAD_VALUE, FEED_NEGATIVE, MAX_COORD_MM};

/// A word value outside its range: the number to report and what was wrong.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{message}")]
pub struct RangeError {
    pub code: u32,
    pub message: String,
}

/// Check the value `v` of an ordinary word with the upper-case address `letter`.
#[inline]
pub fn word_value(letter: u8, v: f64) -> Result<(), RangeError> {
    // Axes, G, M and most letters take any finite value: answered inline on the hot path.
    if v.is_finite()
        && !matches!(
            letter,
            b'F' | b'S' | b'T' | b'D' | b'I' | b'J' | b'K' | b'R'
        )
    {
        return Ok(());
    }
    ranged_word_value(letter, v)
}

/// [`word_value`] for the letters with a range, and any value that is not finite.
fn ranged_word_value(letter: u8, v: f64) -> Result<(), RangeError> {
    let l = char::from(letter);
    let err = |code, message: String| Err(RangeError { code, message });
    if !v.is_finite() {
        return err(BAD_VALUE, format!("{l} value is not a finite number"));
    }
    match letter {
        b'F' if v < 0.0 => err(FEED_NEGATIVE, format!("F{v} out of range: negative")),
        b'S' if v < 0.0 => err(BAD_VALUE, format!("S{v} out of range: negative")),
        b'T' | b'D' if whole_u32(v).is_none() => err(
            BAD_VALUE,
            format!("{l}{v} out of range: a whole number from 0 to 4294967295"),
        ),
        b'I' | b'J' | b'K' if v.abs() > MAX_COORD_MM => err(
            ARC_CENTER_RANGE,
            format!("circle centre parameter {l}{v} outside the data format ±{MAX_COORD_MM}"),
        ),
        b'R' if v.abs() > MAX_COORD_MM => err(
            ARC_RADIUS_RANGE,
            format!("circle radius R{v} outside the data format ±{MAX_COORD_MM}"),
        ),
        _ => Ok(()),
    }
}

/// A programmed dwell time, s: refused when negative, with `code` (20752 after G04, 20751 after
/// `#TIME`; TF5200 diagnosis "Dwell time is out of range of permissible values", whose
/// parameters are the value and the limits in µs). The decoder refuses an evaluated time with
/// it, `ncchannel check` a literal one.
pub fn dwell_time(seconds: f64, code: u32) -> Result<f64, RangeError> {
    if seconds >= 0.0 {
        return Ok(seconds);
    }
    let us = (seconds * 1e6).round();
    Err(RangeError {
        code,
        message: format!("dwell time {us} µs out of the permissible range (lower limit 0 µs)"),
    })
}

/// `v` as a whole number 0..=u32::MAX, if it is one (within 1e-9, as `G01` written `G1.0`).
pub(crate) fn whole_u32(v: f64) -> Option<u32> {
    let r = v.round();
    ((v - r).abs() < 1e-9 && (0.0..=f64::from(u32::MAX)).contains(&r)).then_some(r as u32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_and_their_numbers() {
        assert_eq!(word_value(b'X', -5000.0), Ok(()));
        assert_eq!(word_value(b'F', -1.0).unwrap_err().code, FEED_NEGATIVE);
        assert_eq!(word_value(b'S', -1.0).unwrap_err().code, BAD_VALUE);
        assert_eq!(word_value(b'T', 1.5).unwrap_err().code, BAD_VALUE);
        assert_eq!(word_value(b'D', 5e9).unwrap_err().code, BAD_VALUE);
        assert_eq!(word_value(b'T', 12.0), Ok(()));
        assert_eq!(word_value(b'I', 1e18).unwrap_err().code, ARC_CENTER_RANGE);
        assert_eq!(word_value(b'J', -MAX_COORD_MM), Ok(()));
        assert_eq!(word_value(b'R', 1e6).unwrap_err().code, ARC_RADIUS_RANGE);
        assert_eq!(word_value(b'E', f64::INFINITY).unwrap_err().code, BAD_VALUE);
        assert_eq!(word_value(b'S', f64::NAN).unwrap_err().code, BAD_VALUE);
    }
}
