//! The NC language's fixed tables in one place: every error number the channel raises (ISG's
//! and ours), known G and M functions, address letters and our assignment of the "unexpected
//! control statement" numbers.
//!
//! The ISG numbers are those of the TF5200 diagnosis list (README, "Error numbers"). Where
//! ISG gives only a range (20211–20245) or no number we know of, the numbers below are *our*
//! assignment from the 9xxxx range, documented in the README, so that a client can still tell
//! errors apart. No other file spells an error number: it names one of these.

// ---- ISG numbers -----------------------------------------------------------------------

/// Warning: error writing the object (stream buffer full, write rejected).
pub const WRITE_REJECTED: u32 = 11012;
/// Circle centre parameter (I, J, K) outside the data format (TF5200 diagnosis 20020).
pub const ARC_CENTER_RANGE: u32 = 20020;
/// A full circle programmed with a radius: start and end point coincide, so R leaves the
/// centre undetermined (TF5200 diagnosis 20034).
pub const ARC_FULL_CIRCLE_BY_RADIUS: u32 = 20034;
/// The centre computed from R lies outside the data format (TF5200 diagnosis 20054, whose
/// example is `G02 X1 R1000000`).
pub const ARC_RADIUS_RANGE: u32 = 20054;
/// Unknown G function.
pub const UNKNOWN_G: u32 = 20131;
/// Unknown M function.
pub const UNKNOWN_M: u32 = 20157;
/// NC command or axis name expected: the general syntax error. Also used for a block
/// longer than [`MAX_BLOCK_CHARS`] and for expressions nested deeper than the parser allows.
pub const SYNTAX: u32 = 20200;
/// An axis programmed twice in one block.
pub const AXIS_TWICE: u32 = 20203;
/// Unknown `#` command.
pub const UNKNOWN_COMMAND: u32 = 20209;
/// Main program not found.
pub const MAIN_NOT_FOUND: u32 = 20368;
/// Global subroutine not found.
pub const SUBROUTINE_NOT_FOUND: u32 = 20369;
/// Local subroutine not found.
pub const LOCAL_SUB_NOT_FOUND: u32 = 20373;
/// Control blocks still open at program end.
pub const OPEN_CONTROL_BLOCK: u32 = 20375;
/// M17/M29 where no subroutine runs.
pub const UNEXPECTED_SUB_END: u32 = 20376;
/// M30/M02 inside a subroutine (a warning: the program ends).
pub const UNEXPECTED_PROGRAM_END: u32 = 20377;
/// Memory for variables of one class (V.P., V.L., V.S., V.E.; ours adds P) used up: a
/// declaration or a new variable does not fit (TF5200 diagnosis 20967).
pub const VARIABLE_MEMORY_FULL: u32 = 20967;
/// An array with more indices than variables have (TF5200 diagnosis 20974).
pub const TOO_MANY_INDICES: u32 = 20974;
/// `#TIME` with a dwell time out of range (negative): TF5200 diagnosis 20751.
pub const DWELL_RANGE_TIME: u32 = 20751;
/// G04 with a dwell time out of range (negative): TF5200 diagnosis 20752.
pub const DWELL_RANGE_G04: u32 = 20752;
/// Label defined twice in one program level.
pub const LABEL_TWICE: u32 = 20836;
/// `$GOTO` target not found.
pub const LABEL_NOT_FOUND: u32 = 20840;
/// Streaming data without a correct CR LF line end.
pub const NO_LINE_END: u32 = 21476;
/// Backward jump in a streaming program.
pub const STREAM_BACKWARD_JUMP: u32 = 21477;
/// Loop statement in a streaming program.
pub const STREAM_LOOP: u32 = 21478;
/// Local subroutine call (LL) in a streaming program.
pub const STREAM_LOCAL_CALL: u32 = 21479;
/// An axis end point (or an arc's extent) outside the axis's software limits: the block is
/// refused before it moves (TF5200 diagnosis 21897 "Axis position is out of permissible
/// value range", with the axis, the value and both limits).
pub const SOFT_LIMIT: u32 = 21897;
/// Block search target not found.
pub const SEARCH_NOT_FOUND: u32 = 21532;
/// Invalid `#CACHE` programming.
pub const CACHE_SYNTAX: u32 = 21560;
/// Double programming inside one `#CACHE` command.
pub const CACHE_DOUBLE: u32 = 21561;
/// File cache full.
pub const CACHE_FULL: u32 = 21562;
/// File for the cache not found (or unreadable).
pub const CACHE_FILE_NOT_FOUND: u32 = 21563;
/// File larger than `max_cache_size`.
pub const CACHE_FILE_TOO_LARGE: u32 = 21564;
/// `#FLUSH` while a cross-block function (TRC, spline, HSC) is active.
pub const FLUSH_CROSS_BLOCK: u32 = 21909;
/// An array index outside the declared array (TF5200 diagnosis 21928).
pub const ARRAY_INDEX_RANGE: u32 = 21928;

// ---- Our numbers (no ISG number known) ---------------------------------------------------

/// Expression: division by zero.
pub const EVAL_DIVISION_BY_ZERO: u32 = 90001;
/// Expression: square root of a negative number.
pub const EVAL_SQRT_NEGATIVE: u32 = 90002;
/// Expression: ASIN/ACOS outside -1..1.
pub const EVAL_OUT_OF_DOMAIN: u32 = 90003;
/// Expression: LN/LOG of a non-positive number.
pub const EVAL_LOG_NON_POSITIVE: u32 = 90004;
/// Expression: undefined variable or parameter.
pub const EVAL_UNDEFINED: u32 = 90005;
/// Expression: invalid index.
pub const EVAL_BAD_INDEX: u32 = 90006;
/// Expression: result not finite.
pub const EVAL_NOT_FINITE: u32 = 90007;
/// Subroutine nesting deeper than the channel allows.
pub const NESTING_TOO_DEEP: u32 = 90101;
/// The streaming program is already running (called a second time).
pub const STREAM_ALREADY_ACTIVE: u32 = 90102;
/// End of the main program's file without M30/M02.
pub const MAIN_END_MISSING: u32 = 90103;
/// End of a subroutine's file without M17/M29.
pub const SUB_END_MISSING: u32 = 90104;
/// Program file larger than the store reads.
pub const PROGRAM_TOO_LARGE: u32 = 90110;
/// Program file could not be read.
pub const PROGRAM_UNREADABLE: u32 = 90111;
/// Program name not allowed (absolute or leaving the search path).
pub const PROGRAM_BAD_NAME: u32 = 90112;
/// Circle end point, centre and radius do not agree.
pub const ARC_INCONSISTENT: u32 = 90130;
/// G1/G2/G3 without a programmed feed (or G95 without a spindle speed).
pub const NO_FEED: u32 = 90131;
/// A value out of range (negative feed, non-finite axis value, `$FOR` step 0, …).
pub const BAD_VALUE: u32 = 90132;
/// A G function or `#` command of the ISG dialect that ncchannel does not model: refused
/// by name rather than given a wrong meaning (docs/nc-language.md lists them).
pub const UNSUPPORTED: u32 = 90133;
/// A dwell (G04, `#TIME`) with other words in its block: it must stand alone.
pub const DWELL_NOT_ALONE: u32 = 90134;
/// A word other than an axis programmed twice in one block (F, S, T, D, I, J, K, R, E, or
/// two G functions of one group): 20203's siblings, which ISG numbers we do not know.
pub const WORD_TWICE: u32 = 90135;
/// Tool radius compensation impossible: the radius is not below an inner arc's, offset
/// elements do not meet, no tool data for the D word, or compensation outside G17.
pub const TRC_IMPOSSIBLE: u32 = 90140;
/// `#CACHE` while the file cache is disabled.
pub const CACHE_NOT_ENABLED: u32 = 90160;

/// Longest block the parser accepts, in characters without the line end (TF5200 programming manual).
pub const MAX_BLOCK_CHARS: usize = 4000;

/// Deepest nesting of brackets, unary operators, powers and function calls in one
/// expression. Bounds the parser's recursion so hostile input cannot overflow the stack.
pub const MAX_EXPR_NESTING: u32 = 64;

/// Largest coordinate a word may carry, mm (or program units): ISG keeps positions in
/// 0.1 µm as signed 32-bit numbers, so ±214,748.3647 mm is the data format the TF5200
/// diagnoses 20020 and 20054 speak of. I, J, K beyond it are 20020, R beyond it 20054.
pub const MAX_COORD_MM: f64 = 214_748.364_7;

/// Most elements one `#VAR` array may have. A bigger declaration is refused at parse time
/// (20967), so `check` and the decoder agree; together with the per-class byte budgets of
/// the decoder's variable store it bounds what one line can allocate.
pub const MAX_ARRAY_ELEMENTS: u64 = 100_000;

/// Most indices (dimensions) of an array variable, as ISG arrays have (20974 beyond).
pub const MAX_ARRAY_DIMS: usize = 3;

/// Highest expression tree (operators on the longest path from root to a leaf). Bounds the
/// recursion of evaluating, printing and dropping a tree; a flat chain `1+1+…` of more than
/// this many operators is 20200 "expression too complex".
pub const MAX_EXPR_HEIGHT: u32 = 256;

/// Address letters of ordinary words. The TF5200 manual's words are G M H F S T D X Y Z A B C I J K R E;
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

/// The G functions ncchannel implements, the parser's fast path: motion G0–G3, dwell G4,
/// planes G17–G19, tool radius compensation G40–G42, zero offsets G53–G59, contouring at
/// block end G61, inch/metric G70/G71, absolute/incremental G90/G91, reference point offset
/// G92, feed per minute/revolution G94/G95, spindle speed G97, spline off/on G150/G151,
/// contouring off/on G260/G261. The rest of ISG's list is in [`super::dialect`] (accepted
/// without effect, or refused by name); a number in neither is 20131.
pub const KNOWN_G: &[u32] = &[
    0, 1, 2, 3, 4, 17, 18, 19, 40, 41, 42, 53, 54, 55, 56, 57, 58, 59, 61, 70, 71, 90, 91, 92, 94,
    95, 97, 150, 151, 260, 261,
];

/// G functions that take a value: `G133=<expr>`, `G134=<expr>` (TF5200 "Weighting the ramp
/// times", also written `G134 50`) and the dwell `G04 <seconds>`.
pub const G_WITH_VALUE: &[u32] = &[4, 133, 134];

/// Is `g` one of the implemented G functions ([`KNOWN_G`])?
#[inline]
pub fn is_known_g(g: u32) -> bool {
    matches!(
        g,
        0..=4 | 17..=19 | 40..=42 | 53..=59 | 61 | 70 | 71 | 90..=92 | 94 | 95 | 97 | 150 | 151
            | 260 | 261
    )
}

/// M functions: 0 to 65,535 (TF5200 "User-specific technology functions (M/H)"). M0–M9,
/// M17, M29, M30 have their meaning in the decoder; the others go to the PLC side as
/// events. Above 65,535 and fractional numbers are 20157.
pub fn is_known_m(m: u32) -> bool {
    m <= super::dialect::MAX_M_H
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
    fn known_g_matches_the_table() {
        for g in 0..1000 {
            assert_eq!(is_known_g(g), KNOWN_G.contains(&g), "G{g}");
        }
    }

    #[test]
    fn word_letter_mask_matches_the_list() {
        for b in b'A'..=b'Z' {
            assert_eq!(
                is_word_letter(b),
                WORD_LETTERS.contains(&b),
                "{}",
                b as char
            );
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
