//! The NC language's fixed tables in one place: error numbers, known G and M functions,
//! address letters and our assignment of the "unexpected control statement" numbers.
//!
//! REFERENCE §5 gives the ISG numbers where they are known. Where it only gives a range
//! (20211–20245) or nothing at all (evaluation errors), the numbers below are *our*
//! assignment, documented in the README, so that a client can still tell errors apart.

/// Unknown G function (ISG).
pub const UNKNOWN_G: u32 = 20131;
/// Unknown M function (ISG).
pub const UNKNOWN_M: u32 = 20157;
/// NC command or axis name expected: the general syntax error (ISG). Also used for a block
/// longer than [`MAX_BLOCK_CHARS`] and for expressions nested deeper than the parser allows.
pub const SYNTAX: u32 = 20200;
/// Unknown `#` command (ISG).
pub const UNKNOWN_COMMAND: u32 = 20209;
/// Control blocks still open at program end (ISG).
pub const OPEN_CONTROL_BLOCK: u32 = 20375;
/// Label defined twice in one program level (ISG).
pub const LABEL_TWICE: u32 = 20836;
/// `$GOTO` target not found (ISG).
pub const LABEL_NOT_FOUND: u32 = 20840;
/// Invalid `#CACHE` programming (ISG).
pub const CACHE_SYNTAX: u32 = 21560;
/// Double programming inside one `#CACHE` command (ISG).
pub const CACHE_DOUBLE: u32 = 21561;

/// Longest block the parser accepts, in characters without the line end (REFERENCE §4).
pub const MAX_BLOCK_CHARS: usize = 4000;

/// Deepest nesting of brackets, unary operators, powers and function calls in one
/// expression. Bounds the parser's recursion so hostile input cannot overflow the stack.
pub const MAX_EXPR_NESTING: u32 = 64;

/// Highest expression tree (operators on the longest path from root to a leaf). Bounds the
/// recursion of evaluating, printing and dropping a tree; a flat chain `1+1+…` of more than
/// this many operators is 20200 "expression too complex".
pub const MAX_EXPR_HEIGHT: u32 = 256;

/// Address letters of ordinary words. REFERENCE §4 names G M H F S T D X Y Z A B C I J K R E;
/// we add U V W as further axis names (ISG axis names are configurable and U/V/W are the usual
/// secondary linear axes; `V.` still starts a variable). Q is rejected (20200): ISG uses it for
/// nothing in this dialect's scope.
pub const WORD_LETTERS: &[u8] = b"GMHFSTDXYZABCIJKREUVW";

/// Is `b` (already upper-case) an address letter of an ordinary word?
#[inline]
pub fn is_word_letter(b: u8) -> bool {
    // A 32-bit mask over 'A'..='Z' keeps the hot path free of a table search.
    const MASK: u32 = {
        let mut m = 0u32;
        let mut i = 0;
        while i < WORD_LETTERS.len() {
            m |= 1 << (WORD_LETTERS[i] - b'A');
            i += 1;
        }
        m
    };
    b.is_ascii_uppercase() && MASK & (1 << (b - b'A')) != 0
}

/// G functions the parser accepts (REFERENCE §4): motion G0–G3, dwell G4, planes G17–G19,
/// tool radius compensation G40–G42, zero offsets G53–G59, contouring at block end G61,
/// absolute/incremental G90/G91, ramp time weighting G132–G134, spline off/on G150/G151,
/// contouring off/on G260/G261. Everything else is 20131.
pub const KNOWN_G: &[u32] = &[
    0, 1, 2, 3, 4, 17, 18, 19, 40, 41, 42, 53, 54, 55, 56, 57, 58, 59, 61, 90, 91, 132, 133,
    134, 150, 151, 260, 261,
];

/// G functions that take a value: `G133=<expr>`, `G134=<expr>` (ISG manual "Weighting the
/// ramp times"); seed 003 writes it `G134 50`, which we accept too.
pub const G_WITH_VALUE: &[u32] = &[133, 134];

/// Is `g` a known G function?
pub fn is_known_g(g: u32) -> bool {
    KNOWN_G.contains(&g)
}

/// M functions the parser accepts: M0–M9 (stop, optional stop, program end, spindle,
/// tool change, coolant), M17/M29 (subroutine end), M30 (program end) and M10–M99 as user
/// M functions (handed to the PLC side, no meaning in the emulator). M100 and up, and
/// fractional M numbers, are 20157.
pub fn is_known_m(m: u32) -> bool {
    m <= 99
}

/// A `$` control statement's kind, used for the structure check and its error numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StrayKind {
    Else,
    ElseIf,
    EndIf,
    Case,
    Default,
    Break,
    EndSwitch,
    EndFor,
    EndWhile,
    EndDo,
    Until,
    Continue,
}

impl StrayKind {
    /// Our assignment inside ISG's "unexpected control statement" range 20211–20245: one
    /// number per statement so a log line says which statement was out of place.
    pub fn code(self) -> u32 {
        match self {
            StrayKind::Else => 20211,
            StrayKind::ElseIf => 20212,
            StrayKind::EndIf => 20213,
            StrayKind::Case => 20214,
            StrayKind::Default => 20215,
            StrayKind::Break => 20216,
            StrayKind::EndSwitch => 20217,
            StrayKind::EndFor => 20218,
            StrayKind::EndWhile => 20219,
            StrayKind::EndDo => 20220,
            StrayKind::Until => 20221,
            StrayKind::Continue => 20222,
        }
    }

    /// The statement as written, for messages.
    pub fn keyword(self) -> &'static str {
        match self {
            StrayKind::Else => "$ELSE",
            StrayKind::ElseIf => "$ELSEIF",
            StrayKind::EndIf => "$ENDIF",
            StrayKind::Case => "$CASE",
            StrayKind::Default => "$DEFAULT",
            StrayKind::Break => "$BREAK",
            StrayKind::EndSwitch => "$ENDSWITCH",
            StrayKind::EndFor => "$ENDFOR",
            StrayKind::EndWhile => "$ENDWHILE",
            StrayKind::EndDo => "$ENDDO",
            StrayKind::Until => "$UNTIL",
            StrayKind::Continue => "$CONTINUE",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn word_letter_mask_matches_the_list() {
        for b in b'A'..=b'Z' {
            assert_eq!(is_word_letter(b), WORD_LETTERS.contains(&b), "{}", b as char);
        }
        assert!(!is_word_letter(b'g'));
        assert!(!is_word_letter(b'['));
    }

    #[test]
    fn stray_codes_are_distinct_and_in_isg_range() {
        use StrayKind::*;
        let all = [
            Else, ElseIf, EndIf, Case, Default, Break, EndSwitch, EndFor, EndWhile, EndDo, Until,
            Continue,
        ];
        let mut codes: Vec<u32> = all.iter().map(|k| k.code()).collect();
        assert!(codes.iter().all(|c| (20211..=20245).contains(c)));
        codes.sort();
        codes.dedup();
        assert_eq!(codes.len(), all.len());
    }
}
