//! The NC language's fixed tables in one place: every error id the channel raises, known G
//! and M functions, address letters.
//!
//! An id either means here what it means in the kernel's own error list (the TF5200
//! diagnosis pages, "ID nnnnn", at infosys.beckhoff.com/content/1033/tf5200_diagnosis/) or it
//! lies in 900000–999999, a range the kernel does not use (it uses 0–159999, 220000–319999,
//! 400000–409999, 500000 and 1000000–1001851; 9xxxx holds its tool radius compensation
//! errors). Our own ids are 900000 plus the last digits they had before they left 9xxxx
//! (README "Error numbers"). [`EMITTED`] lists every id ncchannel can emit, [`KERNEL_TITLES`]
//! the published title of each kernel id among them whose page was read and [`KERNEL_UNREAD`]
//! the few whose page is still to be read; the test `every_emitted_id_is_the_kernels_or_ours`
//! holds them together. No other file spells an error number: it names one of these.

// ---- Error ids: the kernel's (TF5200 diagnosis ID page cited) ---------------------------

/// Warning: error writing the object (stream buffer full, write rejected): TF5200 diagnosis
/// ID 11012.
pub const WRITE_REJECTED: u32 = 11012;
/// G1/G2/G3 with path feed 0: no F programmed, or G95 without a spindle speed (TF5200
/// diagnosis ID 20008 "Feed rate in motion block is 0.").
pub const NO_FEED: u32 = 20008;
/// G04 with its time given both directly and by an axis, `G04 10 X2` (TF5200 diagnosis ID
/// 20013 "Dwell time is programmed directly and via coordinate.").
pub const DWELL_DIRECT_AND_AXIS: u32 = 20013;
/// G04 with its time given by an axis other than the first main axis, `G04 Y2` (TF5200
/// diagnosis ID 20014 "Dwell time is not programmed with the coordinate of first axis.").
pub const DWELL_NOT_FIRST_AXIS: u32 = 20014;
/// A warning: a G function that needs an axis in its block programmed without one, `G160=2`
/// (TwinCAT CNC diagnosis ID 20003, "Programmierte G-Funktion nur mit Achsangabe sinnvoll.",
/// class 1: the program goes on).
pub const G_WITHOUT_AXIS: u32 = 20003;
/// G63 (tapping) with spindle speed 0 (TF5200 diagnosis ID 20007 "Spindle speed is 0.", whose
/// example is `G63 Z10 F300 S0`); ncchannel reports it for a literal `S0` in the G63 block and
/// refuses every other G63 by name (it does not model tapping).
pub const SPINDLE_SPEED_0: u32 = 20007;
/// A negative literal speed `REV` in the spindle's brackets, `S[REV -5]` (TF5200 diagnosis ID
/// 20991 "Negative spindle speed not permitted.", for spindle-specific programming `S[...]`).
pub const SPINDLE_SPEED_NEGATIVE: u32 = 20991;
/// Circle centre parameter (I, J, K) outside the data format (TF5200 diagnosis ID 20020).
pub const ARC_CENTER_RANGE: u32 = 20020;
/// A full circle programmed with a radius: start and end point coincide, so R leaves the
/// centre undetermined (TF5200 diagnosis ID 20034).
pub const ARC_FULL_CIRCLE_BY_RADIUS: u32 = 20034;
/// The centre computed from R lies outside the data format (TF5200 diagnosis ID 20054, whose
/// example is `G02 X1 R1000000`).
pub const ARC_RADIUS_RANGE: u32 = 20054;
/// G41 and G42 (or one of them twice) in one block (TF5200 diagnosis ID 20114 "Double
/// programmed selection of tool radius compensation.", whose example is `G41 X10 Y20 G42`).
pub const TRC_TWICE: u32 = 20114;
/// Unknown G function (TF5200 diagnosis ID 20131).
pub const UNKNOWN_G: u32 = 20131;
/// Unknown M function (TF5200 diagnosis ID 20157).
pub const UNKNOWN_M: u32 = 20157;
/// An M function numbered above the self-defined ones ([`MAX_SELF_DEFINED_M`]) that the
/// channel parameters do not define and that is no internal M function either (TF5200
/// diagnosis ID 20160 "Unknown internal M-function.", whose example is `M1001`).
pub const UNKNOWN_INTERNAL_M: u32 = 20160;
/// H function the channel parameters do not define (kernel id 20162; its TF5200 page was not
/// read, see [`KERNEL_UNREAD`]).
pub const UNKNOWN_H: u32 = 20162;
/// A second D word in one block (TF5200 diagnosis ID 20170 "Double-programmed
/// D-function.", whose example is `D1 D2`).
pub const D_TWICE: u32 = 20170;
/// A second F word in one block (TF5200 diagnosis ID 20175 "Double-programmed F-word.").
pub const F_TWICE: u32 = 20175;
/// A negative feed F (kernel id 20176, "negative or zero F", as the kernel's error list names
/// it; its TF5200 diagnosis page was not read, see [`KERNEL_UNREAD`]). F0 itself is accepted
/// as a word: a motion block at feed 0 is [`NO_FEED`].
pub const FEED_NEGATIVE: u32 = 20176;
/// The same M function twice in one block in one scope: `M10 M10`, `S[M10 M10]` (TF5200
/// diagnosis ID 20765 "Double-programmed M-function.", which allows `M10 X[M10] S[M10]`: a
/// channel's, an axis's and a spindle's M function are three).
pub const M_TWICE: u32 = 20765;
/// A circle centre parameter (I, J or K) twice in one block (TF5200 diagnosis ID 20205
/// "Double-programmed centre point coordinate.", whose example is `G02 I10 I20 J30`).
pub const ARC_CENTER_TWICE: u32 = 20205;
/// Expression: square root of a negative number (kernel id 20398 in the kernel's error
/// list; its TF5200 diagnosis page was not read, see [`KERNEL_UNREAD`]).
pub const EVAL_SQRT_NEGATIVE: u32 = 20398;
/// End of the main program's file without M30/M02 (kernel id 21129, "M02/M30 missing" in the
/// kernel's error list; its TF5200 diagnosis page was not read, see [`KERNEL_UNREAD`]).
pub const MAIN_END_MISSING: u32 = 21129;
/// A second S word in one block (TF5200 diagnosis ID 20181 "Double-programmed spindle.",
/// whose example is `S1000 M03 … S1500`).
pub const S_TWICE: u32 = 20181;
/// NC command or axis name expected: the general syntax error (TF5200 diagnosis ID 20200).
/// Also used for a block longer than [`MAX_BLOCK_CHARS`] and for expressions nested deeper
/// than the parser allows.
pub const SYNTAX: u32 = 20200;
/// An axis programmed twice in one block (TF5200 diagnosis ID 20203 "Double-programmed
/// axis.").
pub const AXIS_TWICE: u32 = 20203;
/// A `$` statement with other words in its block (TF5200 diagnosis ID 20206 "$ command must
/// be programmed exclusively in NC block.").
pub const CONTROL_NOT_ALONE: u32 = 20206;
/// A `#` command with other words before it in its block (TF5200 diagnosis ID 20207 "#
/// command must be programmed exclusively in NC block.").
pub const COMMAND_NOT_ALONE: u32 = 20207;
/// Unknown `#` command or `$` statement (TF5200 diagnosis ID 20209; page not yet read, see
/// [`KERNEL_UNREAD`]).
pub const UNKNOWN_COMMAND: u32 = 20209;
/// `$ELSE` without its `$IF` (TF5200 diagnosis ID 20214).
pub const UNEXPECTED_ELSE: u32 = 20214;
/// `$ELSEIF` without its `$IF` (TF5200 diagnosis ID 20216).
pub const UNEXPECTED_ELSEIF: u32 = 20216;
/// `$ENDIF` without its `$IF` (TF5200 diagnosis ID 20218).
pub const UNEXPECTED_ENDIF: u32 = 20218;
/// `$CASE` outside `$SWITCH` (TF5200 diagnosis ID 20221).
pub const UNEXPECTED_CASE: u32 = 20221;
/// `$CASE` with another word after its condition in its block (TF5200 diagnosis ID 20222
/// "After 'CASE' only the condition is permissible.").
pub const CASE_NOT_ALONE: u32 = 20222;
/// `$DEFAULT` outside `$SWITCH` (TF5200 diagnosis ID 20223).
pub const UNEXPECTED_DEFAULT: u32 = 20223;
/// `$ENDSWITCH` without its `$SWITCH` (TF5200 diagnosis ID 20225).
pub const UNEXPECTED_ENDSWITCH: u32 = 20225;
/// `$ENDFOR` without its `$FOR` (TF5200 diagnosis ID 20232).
pub const UNEXPECTED_ENDFOR: u32 = 20232;
/// `$ENDWHILE` without its `$WHILE` (TF5200 diagnosis ID 20237).
pub const UNEXPECTED_ENDWHILE: u32 = 20237;
/// `$ENDDO` without its `$DO` (TF5200 diagnosis ID 20240; page not yet read, see
/// [`KERNEL_UNREAD`]).
pub const UNEXPECTED_ENDDO: u32 = 20240;
/// `$ENDDO` with another word after its condition in its block (TF5200 diagnosis ID 20241
/// "After 'ENDDO' only the condition is permissible.").
pub const ENDDO_NOT_ALONE: u32 = 20241;
/// `$BREAK` outside a loop or `$SWITCH` (TF5200 diagnosis ID 20243).
pub const UNEXPECTED_BREAK: u32 = 20243;
/// `$CONTINUE` outside a loop or `$SWITCH` (TF5200 diagnosis ID 20244).
pub const UNEXPECTED_CONTINUE: u32 = 20244;
/// `$UNTIL` without its `$REPEAT` (TF5200 diagnosis ID 21469; page not yet read, see
/// [`KERNEL_UNREAD`]).
pub const UNEXPECTED_UNTIL: u32 = 21469;
/// `$UNTIL` with another word after its condition in its block (TF5200 diagnosis ID 21470
/// "After 'UNTIL' only the condition is permissible.").
pub const UNTIL_NOT_ALONE: u32 = 21470;
/// Subroutine calls nested deeper than `decoder.max_subroutine_depth` (TF5200 diagnosis ID
/// 20360 "Stack overflow for global sub-routines."; ncchannel counts local calls too).
pub const NESTING_TOO_DEEP: u32 = 20360;
/// Main program not found (TF5200 diagnosis ID 20368).
pub const MAIN_NOT_FOUND: u32 = 20368;
/// Global subroutine not found (TF5200 diagnosis ID 20369).
pub const SUBROUTINE_NOT_FOUND: u32 = 20369;
/// Local subroutine not found (TF5200 diagnosis ID 20373).
pub const LOCAL_SUB_NOT_FOUND: u32 = 20373;
/// A warning: control blocks whose branch ran still open at the program's or a subroutine's
/// end; it ends as programmed (TF5200 diagnosis ID 20375, class 1: processing continues).
pub const OPEN_CONTROL_BLOCK: u32 = 20375;
/// M17/M29 where no subroutine runs (TF5200 diagnosis ID 20376).
pub const UNEXPECTED_SUB_END: u32 = 20376;
/// M30/M02 inside a subroutine, a warning: the program ends (TF5200 diagnosis ID 20377).
pub const UNEXPECTED_PROGRAM_END: u32 = 20377;
/// Expression: division by zero, also `MOD 0` (TF5200 diagnosis ID 20396 "Division by 0.").
pub const EVAL_DIVISION_BY_ZERO: u32 = 20396;
/// Expression: LN/LOG of a number <= 0 (TF5200 diagnosis ID 20399 "Logarithm less
/// than/equal 0.").
pub const EVAL_LOG_NON_POSITIVE: u32 = 20399;
/// Block search: M30/M02 or the end of the file reached before the continuation position
/// (the search target) was found. The TF5200 block search manual ("Exceptions and errors",
/// tf5200_blocksearch/348601995) names P-ERR-20704 for a continuation position not found;
/// its TwinCAT 2 edition quotes the message, "program end reached without restart mark
/// found". The diagnosis page of ID 20704 itself was not in the index searched.
pub const SEARCH_NOT_FOUND: u32 = 20704;
/// The combined assignment `/=` with a divisor of 0, `P2/=P1` (TF5200 diagnosis ID 20574
/// "Division by 0."); a `/` inside an expression is [`EVAL_DIVISION_BY_ZERO`].
pub const COMBINED_DIVISION_BY_ZERO: u32 = 20574;
/// `#FLUSH` while tool radius compensation G41/G42 is active (TF5200 diagnosis ID 20651 "NC
/// command is not allowed during active TRC.", which lists `#FLUSH`; its sibling ID 90050 is
/// the flush right after G40 before a motion block, a state ncchannel does not have).
pub const FLUSH_UNDER_TRC: u32 = 20651;
/// A warning: G04 with further axes beside the first main axis, `G04 X2 Y3`; the dwell takes
/// X's time and the other axes do not move (TF5200 diagnosis ID 20685 "Dwell time
/// programmed with additional axes.", class 1, processing continues).
pub const DWELL_EXTRA_AXES: u32 = 20685;
/// `#MSG`: the values programmed do not match the text's format elements (TF5200 diagnosis
/// ID 20721 "Number of parameters and the number of format specifiers do not match.").
pub const MSG_ARG_COUNT: u32 = 20721;
/// `#MSG`: more format elements than values can be given (TF5200 diagnosis ID 20724 "Too many
/// parameters in the message string."; the limit is `lang::msg::MAX_MSG_VALUES`).
pub const MSG_TOO_MANY_VALUES: u32 = 20724;
/// `#MSG`: a comma not followed by a value (TF5200 diagnosis ID 20726 "After a comma a
/// mathematical expression is expected.").
pub const MSG_NO_VALUE: u32 = 20726;
/// `#MSG`: a format element other than `%s %S %d %D %f %F` (TF5200 diagnosis ID 21232,
/// "Unbekannter Formatstring.", unknown format string).
pub const MSG_UNKNOWN_FORMAT: u32 = 21232;
/// `#TIME` with a dwell time out of range (negative): TF5200 diagnosis ID 20751.
pub const DWELL_RANGE_TIME: u32 = 20751;
/// G04 with a dwell time out of range (negative): TF5200 diagnosis ID 20752.
pub const DWELL_RANGE_G04: u32 = 20752;
/// A warning: more string labels (`[NAME]`) in a program file than its label index holds
/// (`decoder::MAX_INDEXED_LABELS`); the program goes on and a jump to a label that found no
/// room is searched from the top of the file (TF5200 diagnosis ID 20829 "Number of string
/// labels too big for optimised program execution.", class 1, processing continues).
pub const STRING_LABEL_INDEX_FULL: u32 = 20829;
/// Label defined twice in one program level (TF5200 diagnosis ID 20836 "Multiple defined
/// label").
pub const LABEL_TWICE: u32 = 20836;
/// `$GOTO` target not found (TF5200 diagnosis ID 20840).
pub const LABEL_NOT_FOUND: u32 = 20840;
/// Memory for variables of one class (V.P., V.L., V.S., V.E.; ours adds P) used up: a
/// declaration or a new variable does not fit (TF5200 diagnosis ID 20967).
pub const VARIABLE_MEMORY_FULL: u32 = 20967;
/// An array with more indices than variables have (TF5200 diagnosis ID 20974).
pub const TOO_MANY_INDICES: u32 = 20974;
/// A V.E. variable the list of external variables does not declare (the kernel's error list:
/// "unknown variable"; its TF5200 page was not read).
pub const VARIABLE_UNKNOWN: u32 = 20196;
/// A program reads a V.E. variable declared WRITE_ONLY (TF5200 diagnosis ID 20097).
pub const VARIABLE_READ_DENIED: u32 = 20097;
/// A program writes a V.E. variable declared READ_ONLY (TF5200 diagnosis ID 20100).
pub const VARIABLE_WRITE_DENIED: u32 = 20100;
/// A value outside the range of a V.E. variable's type (TF5200 diagnosis ID 20847, with the
/// value and both limits).
pub const VARIABLE_OUT_OF_FORMAT: u32 = 20847;
/// Streaming data without a correct CR LF line end (TF5200 diagnosis ID 21476).
pub const NO_LINE_END: u32 = 21476;
/// Backward jump in a streaming program (TF5200 diagnosis ID 21477).
pub const STREAM_BACKWARD_JUMP: u32 = 21477;
/// Loop statement in a streaming program (TF5200 diagnosis ID 21478).
pub const STREAM_LOOP: u32 = 21478;
/// Local subroutine call (LL) in a streaming program (TF5200 diagnosis ID 21479).
pub const STREAM_LOCAL_CALL: u32 = 21479;
/// A false branch (or a skipped case or loop) still waiting for its end statement when the
/// file of a local subroutine ends (TF5200 diagnosis ID 21500 "There are pending invalid
/// control blocks at local subroutine end.").
pub const OPEN_INVALID_BLOCK_LOCAL: u32 = 21500;
/// As [`OPEN_INVALID_BLOCK_LOCAL`], at the main program's end (TF5200 diagnosis ID 21501).
pub const OPEN_INVALID_BLOCK_MAIN: u32 = 21501;
/// As [`OPEN_INVALID_BLOCK_LOCAL`], at a global subroutine's end (TF5200 diagnosis ID 21502).
pub const OPEN_INVALID_BLOCK_GLOBAL: u32 = 21502;
/// Invalid `#CACHE` programming (TF5200 diagnosis ID 21560).
pub const CACHE_SYNTAX: u32 = 21560;
/// Double programming inside one `#CACHE` command (TF5200 diagnosis ID 21561).
pub const CACHE_DOUBLE: u32 = 21561;
/// File cache full (TF5200 diagnosis ID 21562).
pub const CACHE_FULL: u32 = 21562;
/// File for the cache not found, or unreadable (TF5200 diagnosis ID 21563).
pub const CACHE_FILE_NOT_FOUND: u32 = 21563;
/// File larger than `max_cache_size` (TF5200 diagnosis ID 21564).
pub const CACHE_FILE_TOO_LARGE: u32 = 21564;
/// An axis end point (or an arc's extent) outside the axis's software limits: the block is
/// refused before it moves (TF5200 diagnosis ID 21897 "Axis position is out of permissible
/// value range", with the axis, the value and both limits).
pub const SOFT_LIMIT: u32 = 21897;
/// An array index outside the declared array (TF5200 diagnosis ID 21928).
pub const ARRAY_INDEX_RANGE: u32 = 21928;
/// An operator other than `+` (concatenation), `==` and `!=` with a string operand, or one
/// of those with a string and a number (TF5200 diagnosis ID 21458 "Operator für
/// Zeichenketten nicht erlaubt.": "only the + operator to join two strings or the
/// comparison operators == and != are allowed").
pub const STRING_OPERATOR: u32 = 21458;
/// A string assigned to a `STRING[n]` variable is longer than n (TF5200 diagnosis ID 21462
/// "String for variable too long.", with the length and the maximum).
pub const STRING_TOO_LONG_FOR_VARIABLE: u32 = 21462;
/// A string function's position (or count) outside the string (TF5200 diagnosis ID 21545
/// "Invalid position in character string for string operation.", whose example is
/// `DELETE["Hello world!", 7, 100]`).
pub const STRING_POSITION: u32 = 21545;
/// A string value (a literal, or the result of `+`) longer than the 126 characters a
/// `STRING[n]` may hold (TF5200 diagnosis ID 21870 "String exceeds the maximum length.").
pub const STRING_TOO_LONG: u32 = 21870;
/// `#FLUSH` while a spline (G151) is active (TF5200 diagnosis ID 120102 "Flushing buffers not
/// allowed while spline interpolation is active.").
pub const FLUSH_UNDER_SPLINE: u32 = 120102;
/// `#FLUSH` while `#HSC` is on (TF5200 diagnosis ID 120434, for HSC in its spline mode 2;
/// ncchannel does not tell the HSC modes apart).
pub const FLUSH_UNDER_HSC: u32 = 120434;

// ---- Error ids: ours, 900000–999999 (no kernel id with this meaning read) ----------------

/// Expression: ASIN/ACOS outside -1..1.
pub const EVAL_OUT_OF_DOMAIN: u32 = 900003;
/// Expression: undefined variable or parameter. (Candidates to read: the kernel's 20196; its
/// 20925 "Unknown parameter." covers P parameters only.)
pub const EVAL_UNDEFINED: u32 = 900005;
/// Expression: invalid index (P[0.5], P[-1]).
pub const EVAL_BAD_INDEX: u32 = 900006;
/// Expression: result not finite (`EXP[1000]`, `TAN[90]`).
pub const EVAL_NOT_FINITE: u32 = 900007;
/// Expression: a string (a `STRING[n]` variable, a cycle parameter `@P1="text"`, a literal,
/// a string function's result) used as a number, or stored into a numeric variable.
pub const EVAL_STRING_AS_NUMBER: u32 = 900008;
/// Expression: a number where a string is needed — the text argument of a string function
/// (`LEN[5]`), or a value assigned to a `STRING[n]` variable.
pub const EVAL_NUMBER_AS_STRING: u32 = 900009;
/// The streaming program is already running (called a second time).
pub const STREAM_ALREADY_ACTIVE: u32 = 900102;
/// End of a subroutine's file without M17/M29.
pub const SUB_END_MISSING: u32 = 900104;
/// A warning: more block-number labels (`N10:`) or `%L` sections in a program file than its
/// label index holds; later ones are searched at each jump or call, as for
/// [`STRING_LABEL_INDEX_FULL`], whose kernel id names string labels only.
pub const LABEL_INDEX_FULL: u32 = 900113;
/// Program file larger than the store reads.
pub const PROGRAM_TOO_LARGE: u32 = 900110;
/// Program file could not be read.
pub const PROGRAM_UNREADABLE: u32 = 900111;
/// Program name not allowed (absolute or leaving the search path).
pub const PROGRAM_BAD_NAME: u32 = 900112;
/// Circle end point, centre and radius do not agree.
pub const ARC_INCONSISTENT: u32 = 900130;
/// A value out of range (negative S, non-finite axis value, `$FOR` step 0, T or D not a
/// whole number, …).
pub const BAD_VALUE: u32 = 900132;
/// A G function, `#` command, V.A./V.G. variable, `#FILENAME` file id or modal cycle call
/// of the ISG dialect that ncchannel does not model: refused by name rather than given a
/// wrong meaning (docs/nc-language.md lists them).
pub const UNSUPPORTED: u32 = 900133;
/// A dwell (G04) with a word other than its time and axes in its block (an M, a second G, an
/// assignment, F or S beside the time): refused. The axes have the kernel's ids
/// ([`DWELL_DIRECT_AND_AXIS`], [`DWELL_NOT_FIRST_AXIS`], [`DWELL_EXTRA_AXES`]).
pub const DWELL_NOT_ALONE: u32 = 900134;
/// T, R or E programmed twice in one block (F is [`F_TWICE`], S [`S_TWICE`], D
/// [`D_TWICE`], I J K [`ARC_CENTER_TWICE`], an axis [`AXIS_TWICE`]).
pub const WORD_TWICE: u32 = 900135;
/// A warning: a transformation command in its neutral form (`#TRAFO OFF`, `#CS OFF`, an
/// identity `#CS DEF`/`#CS ON`, `#KIN ID [NONE]`) was accepted and changes nothing
/// (`lang::transform`).
pub const NEUTRAL_TRANSFORMATION: u32 = 900137;
/// A formatted `#MSG` text longer than `lang::msg::MAX_MSG_CHARS`.
pub const MSG_TOO_LONG: u32 = 900136;
/// Tool radius compensation impossible: the radius is not below an inner arc's, offset
/// elements do not meet, no tool data for the D word, or compensation outside G17.
pub const TRC_IMPOSSIBLE: u32 = 900140;
/// `#CACHE` while the file cache is disabled.
pub const CACHE_NOT_ENABLED: u32 = 900160;

// ---- End of the error ids ----------------------------------------------------------------

/// The id for a word other than an axis programmed twice in one block.
pub(crate) fn word_twice(letter: u8) -> u32 {
    match letter.to_ascii_uppercase() {
        b'F' => F_TWICE,
        b'S' => S_TWICE,
        b'D' => D_TWICE,
        b'I' | b'J' | b'K' => ARC_CENTER_TWICE,
        _ => WORD_TWICE,
    }
}

/// Is `code` a `$` statement's own fault ([`UNEXPECTED_ELSEIF`] for a `$ELSEIF` without its
/// condition, [`CASE_NOT_ALONE`], [`ENDDO_NOT_ALONE`], [`UNTIL_NOT_ALONE`]) rather than a
/// general syntax error? Such a line is refused even where it is skipped.
pub(crate) fn is_control_statement_fault(code: u32) -> bool {
    matches!(
        code,
        UNEXPECTED_ELSEIF | CASE_NOT_ALONE | ENDDO_NOT_ALONE | UNTIL_NOT_ALONE
    )
}

/// Every error id ncchannel can emit, with a short meaning: the constants above, once each.
pub const EMITTED: &[(u32, &str)] = &[
    (WRITE_REJECTED, "stream write rejected"),
    (G_WITHOUT_AXIS, "G function without its axis: no effect"),
    (SPINDLE_SPEED_0, "G63 with spindle speed 0"),
    (SPINDLE_SPEED_NEGATIVE, "negative REV in S[...]"),
    (NO_FEED, "feed 0 in a motion block"),
    (DWELL_DIRECT_AND_AXIS, "dwell time direct and by an axis"),
    (
        DWELL_NOT_FIRST_AXIS,
        "dwell time not by the first main axis",
    ),
    (ARC_CENTER_RANGE, "circle centre outside the data format"),
    (ARC_FULL_CIRCLE_BY_RADIUS, "full circle programmed with R"),
    (ARC_RADIUS_RANGE, "centre from R outside the data format"),
    (TRC_TWICE, "G41/G42 twice in a block"),
    (UNKNOWN_G, "unknown G function"),
    (UNKNOWN_M, "unknown M function"),
    (
        UNKNOWN_INTERNAL_M,
        "M above the self-defined range, not internal",
    ),
    (UNKNOWN_H, "unknown H function"),
    (D_TWICE, "D twice in a block"),
    (F_TWICE, "F twice in a block"),
    (FEED_NEGATIVE, "negative F"),
    (M_TWICE, "same M function twice in a block"),
    (ARC_CENTER_TWICE, "I, J or K twice in a block"),
    (S_TWICE, "S twice in a block"),
    (SYNTAX, "syntax"),
    (AXIS_TWICE, "axis twice in a block"),
    (CONTROL_NOT_ALONE, "$ statement not alone in its block"),
    (COMMAND_NOT_ALONE, "# command not alone in its block"),
    (UNKNOWN_COMMAND, "unknown # command"),
    (UNEXPECTED_ELSE, "unexpected $ELSE"),
    (UNEXPECTED_ELSEIF, "unexpected $ELSEIF"),
    (UNEXPECTED_ENDIF, "unexpected $ENDIF"),
    (UNEXPECTED_CASE, "unexpected $CASE"),
    (CASE_NOT_ALONE, "words after the $CASE condition"),
    (UNEXPECTED_DEFAULT, "unexpected $DEFAULT"),
    (UNEXPECTED_ENDSWITCH, "unexpected $ENDSWITCH"),
    (UNEXPECTED_ENDFOR, "unexpected $ENDFOR"),
    (UNEXPECTED_ENDWHILE, "unexpected $ENDWHILE"),
    (UNEXPECTED_ENDDO, "unexpected $ENDDO"),
    (ENDDO_NOT_ALONE, "words after the $ENDDO condition"),
    (UNEXPECTED_BREAK, "unexpected $BREAK"),
    (UNEXPECTED_CONTINUE, "unexpected $CONTINUE"),
    (UNEXPECTED_UNTIL, "unexpected $UNTIL"),
    (UNTIL_NOT_ALONE, "words after the $UNTIL condition"),
    (NESTING_TOO_DEEP, "subroutine nesting too deep"),
    (MAIN_NOT_FOUND, "main program not found"),
    (SUBROUTINE_NOT_FOUND, "global subroutine not found"),
    (LOCAL_SUB_NOT_FOUND, "local subroutine not found"),
    (
        OPEN_CONTROL_BLOCK,
        "open control blocks at program end: a warning",
    ),
    (UNEXPECTED_SUB_END, "M17/M29 in the main program"),
    (UNEXPECTED_PROGRAM_END, "M30/M02 in a subroutine"),
    (EVAL_DIVISION_BY_ZERO, "division by zero"),
    (COMBINED_DIVISION_BY_ZERO, "combined assignment /= by zero"),
    (VARIABLE_UNKNOWN, "V.E. variable not declared"),
    (VARIABLE_READ_DENIED, "V.E. variable WRITE_ONLY read"),
    (VARIABLE_WRITE_DENIED, "V.E. variable READ_ONLY written"),
    (
        VARIABLE_OUT_OF_FORMAT,
        "value outside the V.E. variable's type",
    ),
    (EVAL_SQRT_NEGATIVE, "square root of a negative number"),
    (MAIN_END_MISSING, "main program without M30/M02"),
    (EVAL_LOG_NON_POSITIVE, "logarithm of a number <= 0"),
    (FLUSH_UNDER_TRC, "#FLUSH under tool radius compensation"),
    (
        DWELL_EXTRA_AXES,
        "dwell with further axes: they do not move",
    ),
    (MSG_ARG_COUNT, "#MSG values do not match the format"),
    (MSG_TOO_MANY_VALUES, "#MSG with too many format elements"),
    (MSG_NO_VALUE, "#MSG comma without a value"),
    (MSG_UNKNOWN_FORMAT, "#MSG unknown format element"),
    (DWELL_RANGE_TIME, "#TIME out of range"),
    (DWELL_RANGE_G04, "G04 time out of range"),
    (
        STRING_LABEL_INDEX_FULL,
        "string label index full: later ones searched",
    ),
    (LABEL_TWICE, "label defined twice"),
    (LABEL_NOT_FOUND, "label not found"),
    (VARIABLE_MEMORY_FULL, "variable memory full"),
    (TOO_MANY_INDICES, "too many array indices"),
    (NO_LINE_END, "stream: no CR LF"),
    (STREAM_BACKWARD_JUMP, "stream: backward jump"),
    (STREAM_LOOP, "stream: loop"),
    (STREAM_LOCAL_CALL, "stream: LL call"),
    (SEARCH_NOT_FOUND, "block search target not found"),
    (
        OPEN_INVALID_BLOCK_LOCAL,
        "false branch open at local subroutine end",
    ),
    (
        OPEN_INVALID_BLOCK_MAIN,
        "false branch open at main program end",
    ),
    (
        OPEN_INVALID_BLOCK_GLOBAL,
        "false branch open at global subroutine end",
    ),
    (CACHE_SYNTAX, "#CACHE invalid"),
    (CACHE_DOUBLE, "#CACHE double programming"),
    (CACHE_FULL, "file cache full"),
    (CACHE_FILE_NOT_FOUND, "cache file not found"),
    (CACHE_FILE_TOO_LARGE, "cache file too large"),
    (SOFT_LIMIT, "beyond a software limit"),
    (ARRAY_INDEX_RANGE, "array index outside the array"),
    (STRING_OPERATOR, "operator not allowed for strings"),
    (
        STRING_TOO_LONG_FOR_VARIABLE,
        "string too long for its variable",
    ),
    (STRING_POSITION, "string position outside the string"),
    (STRING_TOO_LONG, "string longer than 126 characters"),
    (FLUSH_UNDER_SPLINE, "#FLUSH under spline"),
    (FLUSH_UNDER_HSC, "#FLUSH under #HSC"),
    (EVAL_OUT_OF_DOMAIN, "ASIN/ACOS outside -1..1"),
    (EVAL_UNDEFINED, "undefined variable"),
    (EVAL_BAD_INDEX, "invalid index"),
    (EVAL_NOT_FINITE, "result not finite"),
    (EVAL_STRING_AS_NUMBER, "string used as a number"),
    (EVAL_NUMBER_AS_STRING, "number used as a string"),
    (STREAM_ALREADY_ACTIVE, "streaming program already running"),
    (SUB_END_MISSING, "subroutine without M17/M29"),
    (
        LABEL_INDEX_FULL,
        "N label or %L section index full: later ones searched",
    ),
    (PROGRAM_TOO_LARGE, "program file too large"),
    (PROGRAM_UNREADABLE, "program file unreadable"),
    (PROGRAM_BAD_NAME, "program name leaves the search path"),
    (ARC_INCONSISTENT, "circle inconsistent"),
    (BAD_VALUE, "value out of range"),
    (UNSUPPORTED, "dialect function refused by name"),
    (DWELL_NOT_ALONE, "dwell not alone in its block"),
    (WORD_TWICE, "T, R or E twice in a block"),
    (
        NEUTRAL_TRANSFORMATION,
        "neutral transformation command: no effect",
    ),
    (MSG_TOO_LONG, "formatted #MSG text too long"),
    (TRC_IMPOSSIBLE, "tool radius compensation impossible"),
    (CACHE_NOT_ENABLED, "#CACHE without the file cache"),
];

/// Our own ids: a range the kernel's list does not use.
pub const OURS: std::ops::RangeInclusive<u32> = 900000..=999999;

/// Kernel ids ncchannel emits whose diagnosis page was read, each with the title the page
/// publishes and, in the comment, the page (infosys.beckhoff.com/content/1033/ +
/// `tf5200_diagnosis/<n>.html` unless another manual is named). English titles; 20054's,
/// 21232's and 21458's English pages are not in the index searched, so their German titles
/// (content/1031/) stand. 20704's diagnosis page was not in the index either: its message
/// is the one the TwinCAT 2 block search manual quotes (content/1033/blocksearch/
/// 15328482315, "Exceptions / Errors"), whose TF5200 edition names the same id.
pub const KERNEL_TITLES: &[(u32, &str)] = &[
    (11012, "Failure to write object."), // datastreaming/15421096203 "Error messages"
    (
        20003,
        "Programmierte G-Funktion nur mit Achsangabe sinnvoll.",
    ), // TwinCAT CNC diagnosis, German: 1031/tccncdiagnosis/15651573131 "ID-Bereich 20000-20249"
    (20007, "Spindle speed is 0."),      // 250510731
    (20008, "Feed rate in motion block is 0."), // 250515083
    (
        20013,
        "Dwell time is programmed directly and via coordinate.",
    ), // 250532491
    (
        20014,
        "Dwell time is not programmed with the coordinate of first axis.",
    ), // 250536843
    (
        20020,
        "Circle centre point parameter outside permissible data format.",
    ), // 250558603
    (
        20034,
        "Programming of a full circle with radius specification not possible.",
    ), // 250602123
    (
        20054,
        "Korrigierter Mittelpunkt außerhalb erlaubtem Datenformat.",
    ), // 1031: 250663051
    (20097, "Variable lesen nicht erlaubt."), // 1031: 250750091
    (20100, "Write access to variable denied."), // 250758795
    (
        20114,
        "Double programmed selection of tool radius compensation.",
    ), // 250815371
    (20131, "Unknown G function"),       // named so on the page of ID 20107, 250784907
    (20160, "Unknown internal M-function."), // 250945931
    (20170, "Double-programmed D-function."), // 250985099
    (20175, "Double-programmed F-word."), // 250998155
    (20181, "Double-programmed spindle."), // 251019915
    (20203, "Double-programmed axis."),  // 251085195
    (20205, "Double-programmed centre point coordinate."), // 251089547
    (
        20206,
        "$ command must be programmed exclusively in NC block.",
    ), // 251093899
    (
        20207,
        "# command must be programmed exclusively in NC block.",
    ), // 251098251
    (
        20214,
        "Unexpected ELSE. Does not match the current control block.",
    ), // 251124363
    (
        20216,
        "Unexpected ELSEIF. Does not match the current control block.",
    ), // 251133067
    (
        20218,
        "Unexpected ENDIF. Does not match the current control block.",
    ), // 251141771
    (
        20221,
        "Unexpected CASE. Does not match the current control block.",
    ), // 251154827
    (20222, "After 'CASE' only the condition is permissible."), // 251159179
    (
        20223,
        "Unexpected DEFAULT. Does not match the current control block.",
    ), // 251163531
    (
        20225,
        "Unexpected ENDSWITCH. Does not match the current control block.",
    ), // 251172235
    (
        20232,
        "Unexpected ENDFOR. Does not match the current control block.",
    ), // 251202699
    (
        20237,
        "Unexpected ENDWHILE. Does not match the current control block.",
    ), // 251224459
    (20241, "After 'ENDDO' only the condition is permissible."), // 251241867
    (20243, "Unexpected 'BREAK'. No valid/open control blocks."), // 251250571
    (
        20244,
        "Unexpected 'CONTINUE'. No valid/open control blocks.",
    ), // 251254923
    (20360, "Stack overflow for global sub-routines."), // 251402891
    (20375, "There are valid open control blocks at program end."), // 251459467
    (20396, "Division by 0."),           // 251507339
    (20399, "Logarithm less than/equal 0."), // 251520395
    (20574, "Division by 0."),           // 251868555
    (20651, "NC command is not allowed during active TRC."), // 252112267
    (20685, "Dwell time programmed with additional axes."), // 252216715
    (20765, "Double-programmed M-function."), // 252469131
    (20704, "program end reached without restart mark found"), // blocksearch/15328482315
    (
        20721,
        "Number of parameters and the number of format specifiers do not match.",
    ), // 252329867
    (20724, "Too many parameters in the message string."), // 252342923
    (
        20726,
        "After a comma a mathematical expression is expected.",
    ), // 252347275
    (20751, "Dwell time is out of range of permissible values."), // 252425611
    (20752, "Dwell time is out of range of permissible values."), // 252429963
    (20765, "Double-programmed M-function."), // 252469131
    (
        20829,
        "Number of string labels too big for optimised program execution.",
    ), // 252695435
    (20836, "Multiple defined label"),   // 252721547
    (20847, "Value of variable is out of data format."), // 252765067
    (
        20967,
        "Memory for variables limited, allocation of new variable impossible.",
    ), // 253126283
    (20974, "Too many indices in variable array programmed."), // 253143691
    (20991, "Negative spindle speed not permitted."), // 253182859
    (
        21476,
        "Streaming data does not contain a correct line end marker",
    ), // tf5200_data_streaming/222589963
    (21470, "After 'UNTIL' only the condition is permissible."), // 254806155
    (
        21500,
        "There are pending invalid control blocks at local subroutine end.",
    ), // 254941067
    (
        21501,
        "There are pending invalid control blocks at main program end.",
    ), // 254945419
    (
        21502,
        "There are pending invalid control blocks at global subroutine end.",
    ), // 254949771
    (21477, "Backward jump during streaming not allowed."), // 254836619
    (21478, "Loop during streaming not allowed."), // 254840971
    (
        21479,
        "Call of local subroutine during streaming not allowed.",
    ), // 254845323
    (21232, "Unbekannter Formatstring."), // content/1031/tf5200_diagnosis/253866123
    (21928, "Array index is out of data range."), // 256586123
    (21458, "Operator für Zeichenketten nicht erlaubt."), // content/1031/tf5200_diagnosis/254753931
    (21462, "String for variable too long."), // 254771339
    (
        21545,
        "Invalid position in character string for string operation.",
    ), // 255136907
    (21870, "String exceeds the maximum length."), // 256359819
    (
        120102,
        "Flushing buffers not allowed while spline interpolation is active.",
    ), // 264284811
    (
        120434,
        "While HSC function is active with mode 2 flushing NC channel is not permitted.",
    ), // 264720011
];

/// Kernel ids ncchannel emits whose diagnosis page the searched index did not return, with the
/// meaning ncchannel gives them. All but two were assigned before the id table existed;
/// 20240 and 21469 sit between pages that were read (20239 "'DO' must be programmed
/// exclusively", 20241 "After 'ENDDO' only the condition is permissible"; 21470 "After
/// 'UNTIL' only the condition is permissible"), in the kernel's pattern of "Unexpected X"
/// before "X must be programmed exclusively". What the neighbours say of two of them: the
/// page after 20157 that was read, 20160 "Unknown internal M-function." (250945931), is an
/// M number above the user range that is no internal M function either; and the TwinCAT 2
/// CNC diagnosis list (content/1033/tccncdiagnosis/15651576715, "ID-range 20500-20749")
/// gives 20509 "Unknown NC-command after #.", while the TF5200 pages of neither 20209 nor
/// 20509 were in the index, so which of the two the current kernel raises for an unknown
/// `#` command is open. Each stays here until its page is read and it moves to
/// [`KERNEL_TITLES`] (or, if it means something else, to our range).
pub const KERNEL_UNREAD: &[(u32, &str)] = &[
    (20157, "unknown M function"),
    // The kernel's id for an H function the channel does not define, as reported for the
    // TwinCAT CNC; its TF5200 diagnosis page was not read.
    (20162, "unknown H function"),
    (20196, "unknown variable"),
    // 20176, 20398 and 21129 are named so in the kernel's error list; their TF5200 diagnosis
    // pages were not in the index searched.
    (20176, "negative or zero F"),
    (20398, "square root of a negative value"),
    (21129, "M02/M30 missing"),
    (20200, "NC command or axis name expected"),
    (20209, "unknown # command or $ statement"),
    (20240, "unexpected $ENDDO"),
    (20368, "main program not found"),
    (20369, "global subroutine not found"),
    (20373, "local subroutine not found"),
    (20376, "M17/M29 where no subroutine runs"),
    (20377, "M30/M02 inside a subroutine"),
    (20840, "label not found"),
    (21469, "unexpected $UNTIL"),
    (21560, "invalid #CACHE programming"),
    (21561, "double programming in #CACHE"),
    (21562, "file cache full"),
    (21563, "cache file not found"),
    (21564, "cache file too large"),
    (21897, "axis position out of the permissible range"),
];

/// Longest block the parser accepts, in characters without the line end (TF5200 programming manual).
pub const MAX_BLOCK_CHARS: usize = 4000;

/// Deepest nesting of brackets, unary operators, powers and function calls in one
/// expression. Bounds the parser's recursion so hostile input cannot overflow the stack.
pub(crate) const MAX_EXPR_NESTING: u32 = 64;

/// Largest coordinate a word may carry, mm (or program units): ISG keeps positions in
/// 0.1 µm as signed 32-bit numbers, so ±214,748.3647 mm is the data format the TF5200
/// diagnoses 20020 and 20054 speak of. I, J, K beyond it are 20020, R beyond it 20054.
pub(crate) const MAX_COORD_MM: f64 = 214_748.364_7;

/// Most elements one `#VAR` array may have. A bigger declaration is refused at parse time
/// (20967), so `check` and the decoder agree; together with the per-class byte budgets of
/// the decoder's variable store it bounds what one line can allocate.
pub(crate) const MAX_ARRAY_ELEMENTS: u64 = 100_000;

/// Most indices (dimensions) of an array variable, as ISG arrays have (20974 beyond).
pub(crate) const MAX_ARRAY_DIMS: usize = 3;

/// Highest expression tree (operators on the longest path from root to a leaf). Bounds the
/// recursion of evaluating, printing and dropping a tree; a flat chain `1+1+…` of more than
/// this many operators is 20200 "expression too complex".
pub(crate) const MAX_EXPR_HEIGHT: u32 = 256;

/// Address letters of ordinary words. The TF5200 manual's words are G M H F S T D X Y Z A B C I J K R E;
/// we add U V W as further axis names (ISG axis names are configurable and U/V/W are the usual
/// secondary linear axes; `V.` still starts a variable). Q is rejected (20200): ISG uses it for
/// nothing in this dialect's scope.
pub const WORD_LETTERS: &[u8] = b"GMHFSTDXYZABCIJKREUVW";

/// Is `b` (already upper-case) an address letter of an ordinary word?
#[inline]
pub(crate) fn is_word_letter(b: u8) -> bool {
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
/// circle centre absolute/relative G161/G162, contouring off/on G260/G261. The rest of ISG's list is in [`super::dialect`] (accepted
/// without effect, or refused by name); a number in neither is 20131.
pub const KNOWN_G: &[u32] = &[
    0, 1, 2, 3, 4, 17, 18, 19, 40, 41, 42, 53, 54, 55, 56, 57, 58, 59, 61, 70, 71, 90, 91, 92, 94,
    95, 97, 150, 151, 161, 162, 260, 261,
];

/// G functions that take a value: `G133=<expr>`, `G134=<expr>` (TF5200 "Weighting the ramp
/// times", also written `G134 50`), `G129=<expr>` (weighting of rapid traverse velocity),
/// `G131=<expr>` / `G231=<expr>` (acceleration weighting, TF5200 "Acceleration weighting"),
/// `G233=<expr>` (weighting for G00) and the dwell `G04 <seconds>`.
pub(crate) const G_WITH_VALUE: &[u32] = &[4, 129, 131, 133, 134, 231, 233];

/// Is `g` one of the implemented G functions ([`KNOWN_G`])?
#[inline]
pub(crate) fn is_known_g(g: u32) -> bool {
    matches!(
        g,
        0..=4 | 17..=19 | 40..=42 | 53..=59 | 61 | 70 | 71 | 90..=92 | 94 | 95 | 97 | 150 | 151
            | 161 | 162 | 260 | 261
    )
}

/// M functions: 0 to 65,535 (TF5200 "User-specific technology functions (M/H)"). M0–M9,
/// M17, M29, M30 have their meaning in the decoder; the others go to the PLC side as
/// events. Above 65,535 and fractional numbers are 20157.
pub(crate) fn is_known_m(m: u32) -> bool {
    m <= MAX_M_H
}

/// M and H functions: 0 to 65,535 (TF5200 "User-specific technology functions (M/H)").
pub(crate) const MAX_M_H: u32 = 65_535;

/// The highest self-defined M function: the kernel's table of them has 1000 entries
/// (TF5200 channel parameters, P-CHAN-00041: `m_synch[i]` with i = 0 … 999). An undefined M
/// above it is [`UNKNOWN_INTERNAL_M`], one up to it [`UNKNOWN_M`]; ncchannel's lists may define
/// M functions above it too (docs/design-choices.md).
pub(crate) const MAX_SELF_DEFINED_M: u32 = 999;

/// The id of an M function the channel parameters do not define: 20157, or 20160 above the
/// self-defined ones, where the kernel looks for an internal M function.
pub(crate) fn unknown_m(m: u32) -> u32 {
    if m > MAX_SELF_DEFINED_M {
        UNKNOWN_INTERNAL_M
    } else {
        UNKNOWN_M
    }
}

/// A `$` control statement's kind, used for the structure check and its error numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum StrayKind {
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
    /// The kernel's "unexpected control statement" id of this statement (TF5200 diagnosis
    /// IDs 20214–20244 and 21469, one per statement).
    pub fn code(self) -> u32 {
        match self {
            StrayKind::Else => UNEXPECTED_ELSE,
            StrayKind::ElseIf => UNEXPECTED_ELSEIF,
            StrayKind::EndIf => UNEXPECTED_ENDIF,
            StrayKind::Case => UNEXPECTED_CASE,
            StrayKind::Default => UNEXPECTED_DEFAULT,
            StrayKind::Break => UNEXPECTED_BREAK,
            StrayKind::EndSwitch => UNEXPECTED_ENDSWITCH,
            StrayKind::EndFor => UNEXPECTED_ENDFOR,
            StrayKind::EndWhile => UNEXPECTED_ENDWHILE,
            StrayKind::EndDo => UNEXPECTED_ENDDO,
            StrayKind::Until => UNEXPECTED_UNTIL,
            StrayKind::Continue => UNEXPECTED_CONTINUE,
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
    fn stray_codes_are_distinct_and_the_kernels() {
        use StrayKind::*;
        let all = [
            Else, ElseIf, EndIf, Case, Default, Break, EndSwitch, EndFor, EndWhile, EndDo, Until,
            Continue,
        ];
        let mut codes: Vec<u32> = all.iter().map(|k| k.code()).collect();
        for (k, c) in all.iter().zip(&codes) {
            let word = k.keyword().trim_start_matches('$');
            let title = KERNEL_TITLES
                .iter()
                .chain(KERNEL_UNREAD)
                .find(|(id, _)| id == c)
                .map(|(_, t)| t.to_ascii_uppercase());
            assert!(
                title.as_deref().is_some_and(|t| t.contains(word)),
                "{} is {c}, whose kernel meaning is {title:?}",
                k.keyword()
            );
        }
        codes.sort_unstable();
        codes.dedup();
        assert_eq!(codes.len(), all.len());
    }

    /// Every id ncchannel emits is a kernel id whose meaning is recorded (with its published
    /// title where the page was read), or lies in our range; no id is listed twice.
    #[test]
    fn every_emitted_id_is_the_kernels_or_ours() {
        let mut ids: Vec<u32> = EMITTED.iter().map(|(id, _)| *id).collect();
        for (id, meaning) in EMITTED {
            let read = KERNEL_TITLES.iter().any(|(k, _)| k == id);
            let unread = KERNEL_UNREAD.iter().any(|(k, _)| k == id);
            let ours = OURS.contains(id);
            assert_eq!(
                u8::from(read) + u8::from(unread) + u8::from(ours),
                1,
                "{id} ({meaning}): read {read}, unread {unread}, ours {ours}"
            );
        }
        ids.sort_unstable();
        ids.dedup();
        assert_eq!(ids.len(), EMITTED.len(), "an id is listed twice");
        for (k, title) in KERNEL_TITLES.iter().chain(KERNEL_UNREAD) {
            assert!(!title.is_empty(), "{k}");
            assert!(
                ids.binary_search(k).is_ok(),
                "{k} is recorded but never emitted"
            );
        }
    }

    /// The ids whose page is still to be read: a new one is a deliberate change of this list.
    #[test]
    fn unread_kernel_ids_are_the_known_few() {
        let unread: Vec<u32> = KERNEL_UNREAD.iter().map(|(id, _)| *id).collect();
        assert_eq!(
            unread,
            [
                20157, 20162, 20196, 20176, 20398, 21129, 20200, 20209, 20240, 20368, 20369, 20373,
                20376, 20377, 20840, 21469, 21560, 21561, 21562, 21563, 21564, 21897
            ]
        );
    }

    /// [`EMITTED`] holds every error id constant this file declares, read from its text.
    #[test]
    fn every_error_constant_is_in_the_table() {
        let text = include_str!("codes.rs");
        let start = text.find("// ---- Error ids").expect("start marker");
        let end = text
            .find("// ---- End of the error ids")
            .expect("end marker");
        let mut seen = 0;
        for line in text[start..end].lines() {
            let Some(rest) = line.strip_prefix("pub const ") else {
                continue;
            };
            let (name, value) = rest.split_once(": u32 = ").expect("a u32 constant");
            let value: u32 = value.trim_end_matches(';').parse().expect("a number");
            assert!(
                EMITTED.iter().any(|(id, _)| *id == value),
                "{name} = {value} missing from EMITTED"
            );
            seen += 1;
        }
        assert_eq!(
            seen,
            EMITTED.len(),
            "EMITTED lists an id no constant declares"
        );
    }

    #[test]
    fn word_twice_names_f_and_s_by_the_kernels_ids() {
        assert_eq!(word_twice(b'F'), F_TWICE);
        assert_eq!(word_twice(b's'), S_TWICE);
        assert_eq!(word_twice(b'T'), WORD_TWICE);
    }
}
