//! Constructs of real ISG programs (TF5200 programming manual; the test programs of ISG's
//! editor support `isg-stuttgart/vscode-isg-cnc`, `src/test/res/*.nc`): each one run from a
//! file and streamed — whole and one line per packet — with `check` agreeing with the run.

use crate::support::{feeder, Rig, RunResult};
use ncchannel::channel::Finish;
use ncchannel::lang::*;

/// `text` run from a file, streamed in large packets and streamed one line per packet. Every
/// run must finish the same way with the same blocks; returns the file run.
fn run_everywhere(rig: &Rig, text: &str) -> RunResult {
    rig.program("t.nc", text);
    let file = rig.run("t.nc", None, 1_000_000);
    let one_per_packet: String = text.lines().map(|l| format!("{l}\n\x0c 2\n")).collect();
    for (how, input) in [
        ("large packets", text.to_string()),
        ("line per packet", one_per_packet),
    ] {
        let s = rig.run("streaming.nc", Some(feeder(&input, 992, 1)), 1_000_000);
        assert_eq!(s.finish, file.finish, "{how}: {}\n{}", text, s.log);
        if file.finish == Some(Finish::Ended) {
            assert_eq!(s.block_texts(), file.block_texts(), "{how}: {text}");
        }
        assert_eq!(error_places(&s), error_places(&file), "{how}: {text}");
    }
    file
}

/// (code, line, column) of each error event; the column is the message's "(column N)".
fn error_places(r: &RunResult) -> Vec<(u64, u64, u64)> {
    r.of("error")
        .iter()
        .map(|e| {
            let msg = e["msg"].as_str().unwrap_or("");
            let col = msg
                .rsplit_once("(column ")
                .and_then(|(_, c)| c.trim_end_matches(')').parse().ok())
                .unwrap_or(0);
            (
                e["code"].as_u64().unwrap_or(0),
                e["line"].as_u64().unwrap_or(0),
                col,
            )
        })
        .collect()
}

/// (line, column, code) of each finding of `check`.
fn check_places(text: &str) -> Vec<(usize, usize, u32)> {
    check_program(text)
        .into_iter()
        .map(|d| (d.line, d.col, d.code))
        .collect()
}

/// A program that must run to its end everywhere and check clean.
fn runs_clean(rig: &Rig, text: &str) -> RunResult {
    assert_eq!(check_places(text), [], "check: {text}");
    let r = run_everywhere(rig, text);
    assert_eq!(r.finish, Some(Finish::Ended), "{text}\n{}", r.log);
    r
}

/// A program that fails with one error, the same in check (when `check_sees`) and every run.
fn fails_at(rig: &Rig, text: &str, code: u32, line: usize, col: usize, check_sees: bool) {
    let r = run_everywhere(rig, text);
    assert_eq!(r.finish, Some(Finish::Error), "{text}\n{}", r.log);
    assert_eq!(
        error_places(&r),
        [(u64::from(code), line as u64, col as u64)],
        "{text}"
    );
    if check_sees {
        assert_eq!(check_places(text), [(line, col, code)], "check: {text}");
    }
}

#[test]
fn program_heads_with_a_blank_or_a_title() {
    for (line, name, title) in [
        ("% 100", "100", ""),
        (
            "% TestProgram for streaming mode",
            "TestProgram",
            "for streaming mode",
        ),
        ("%Test - Achsen", "Test", "- Achsen"),
        ("% 100 (comment)", "100", ""),
        ("%L UP1   title words ; comment", "UP1", "title words"),
    ] {
        let b = parse_block(line).unwrap_or_else(|e| panic!("{line}: {e}"));
        let Body::ProgramHead(head) = &b.body else {
            panic!("{line}: {b:?}")
        };
        assert_eq!(
            (head.name.as_str(), head.title.as_str()),
            (name, title),
            "{line}"
        );
        assert_eq!(parse_block(&b.to_string()).unwrap(), b, "{line}");
    }
    let rig = Rig::new();
    for head in [
        "% 100",
        "% TestProgram for streaming mode",
        "%Test - Achsen",
        "% 100 (comment)",
    ] {
        let r = runs_clean(&rig, &format!("{head}\nN10 G01 X10 F1000\nM30\n"));
        assert_eq!(r.position('X'), 10.0, "{head}");
    }
}

#[test]
fn a_backslash_continues_the_block_in_the_next_line() {
    let rig = Rig::new();
    // A DIN block; the continuation line may bring a block number of its own.
    let r = runs_clean(&rig, "N10 G01 F1000 \\\nN20 X10 Y20\nM30\n");
    assert_eq!((r.position('X'), r.position('Y')), (10.0, 20.0));
    assert_eq!(r.block_texts().len(), 2, "{:?}", r.block_texts());
    // Comments after the `\`, and blank or comment lines between the lines of a block.
    let r = runs_clean(
        &rig,
        "G01 X1 \\ (more follows)\n\n; a note\n  Y2 \\\n  F500\nM30\n",
    );
    assert_eq!((r.position('X'), r.position('Y')), (1.0, 2.0));
    // A `\` inside a comment continues nothing.
    let r = runs_clean(&rig, "G01 X3 F100 ; not continued \\\nY4\nM30\n");
    assert_eq!(r.block_texts().len(), 3);
    // L CYCLE [...] over several lines.
    rig.program("c.cyc", "G01 X[@P1] Y[@P2] F1000\nM17\n");
    let r = runs_clean(&rig, "L CYCLE [NAME=c.cyc \\\n  @P1=5 \\\n  @P2=7 ]\nM30\n");
    assert_eq!((r.position('X'), r.position('Y')), (5.0, 7.0));
    // A #VAR initialiser over two lines.
    let r = runs_clean(
        &rig,
        "#VAR\n  V.L.N = 1 + \\\n    2\n#ENDVAR\nG01 X[V.L.N] F100\nM30\n",
    );
    assert_eq!(r.position('X'), 3.0);
}

#[test]
fn an_error_in_a_continued_block_names_the_line_it_stands_in() {
    let rig = Rig::new();
    fails_at(
        &rig,
        "G01 X1 F100\nN10 G01 F1000 \\\nN20 X10 Q5\nM30\n",
        20200,
        3,
        9,
        true,
    );
    fails_at(&rig, "G01 X1 F100 \\\n\n  Y2 X3\nM30\n", 20203, 3, 6, true);
    // The block limit holds for the joined block: 4000 characters, the 4001st is refused
    // in the line it stands in.
    let line = format!("{}\\\n", "X1 ".repeat(300).replace("X1", "G1"));
    let text = format!("{}M30\n", line.repeat(6));
    fails_at(&rig, &text, 20200, 5, 4001 - 4 * 901, true);
}

#[test]
fn an_address_takes_a_parameter_expression_without_brackets() {
    let rig = Rig::new();
    let r = runs_clean(
        &rig,
        "P1=10 P2=1 P10=1 P20=2\nG01 XP1*SIN[P2 * 30]*2 YP10+P20 F1000\nM30\n",
    );
    assert!((r.position('X') - 10.0).abs() < 1e-9, "{}", r.position('X'));
    assert_eq!((r.position('Y'), r.position('Z')), (3.0, 0.0));
    let r = runs_clean(
        &rig,
        "#VAR\n  V.P.TOOLNR = 7\n  V.L.x = 4\n#ENDVAR\nM6 TV.P.TOOLNR\nG01 XV.L.x Y-V.L.X F100\nM30\n",
    );
    assert_eq!(r.machine.channels()[0].report().modal.tool, 7);
    assert_eq!((r.position('X'), r.position('Y')), (4.0, -4.0));
    // The value ends at the blank: what follows is the next word.
    let b = parse_block("XP1 +2").unwrap_err();
    assert_eq!((b.code, b.col), (20200, 5), "{}", b.message);
    fails_at(&rig, "P1=1\nG01 XP1*[P1 Y2 F100\nM30\n", 20200, 2, 13, true);
    // An undefined variable is the run's error, at the word.
    fails_at(
        &rig,
        "G01 X1 F100\nG01 YV.L.NOPE\nM30\n",
        900005,
        2,
        5,
        false,
    );
    // G, M and H still take literal numbers only.
    assert_eq!(parse_block("MP1").unwrap_err().code, 20157);
}

#[test]
fn an_m_function_takes_a_value_carried_with_its_event() {
    let rig = Rig::new();
    std::fs::write(
        rig.startup().with_file_name("channel1.lis"),
        "streaming_prog_file streaming.nc\nm_synch[200] MOS\nm_synch[201] MOS\n\
         h_synch[20] MOS\nh_synch[21] MOS\n",
    )
    .unwrap();
    let r = runs_clean(
        &rig,
        "P1=3\nG01 X1 F100 M200=1200\nM201 = P1*2 H20=5 H21\nM30\n",
    );
    let of = |kind: &str| -> Vec<(u64, Option<i64>)> {
        r.of("techno_output")
            .iter()
            .filter(|e| e["kind"] == kind)
            .map(|e| (e["number"].as_u64().unwrap(), e["value"].as_i64()))
            .collect()
    };
    assert_eq!(of("m"), [(200, Some(1200)), (201, Some(6))]);
    assert_eq!(of("h"), [(20, Some(5)), (21, None)]);
    // The kernel's own M3 and an S the channel list does not hand to the PLC: no output.
    let r = runs_clean(&rig, "M3 S1000\nM30\n");
    assert_eq!(r.of("techno_output").len(), 0);
    // The number is still checked; an undefined value is the run's error at the M.
    fails_at(&rig, "G01 X1 F100\nM70000=1\nM30\n", 20157, 2, 1, true);
    fails_at(&rig, "G01 X1 F100\nX2 M200=P9\nM30\n", 900005, 2, 4, false);
}

#[test]
fn an_axis_takes_an_expression_after_an_equals_sign() {
    let rig = Rig::new();
    let r = runs_clean(&rig, "P1=3\nG01 X=10 Y = P1+2 F100\nZ =-P1 * 2\nM30\n");
    assert_eq!(
        (r.position('X'), r.position('Y'), r.position('Z')),
        (10.0, 5.0, -6.0)
    );
    // `A1 = 0` names the axis A1 (a name of more than one character takes `=`), which this
    // channel does not have: 20200 at the name in a run; `check` has no channel to ask.
    fails_at(&rig, "G01 X1 F100\nA1 = 0\nM30\n", 20200, 2, 1, false);
    assert_eq!(check_places("G01 X1 F100\nA1 = 0\nM30\n"), []);
    // F, S and the other addresses keep their plain form.
    assert_eq!(parse_block("F=100").unwrap_err().col, 2);
}

#[test]
fn var_declarations_take_types_lists_and_block_numbers() {
    let rig = Rig::new();
    let r = runs_clean(
        &rig,
        "#VAR\n\
         \x20 V.P.VAR_1\n\
         \x20 V.P.VAR_3 : UNS32 = 10\n\
         \x20 V.L.NAME_1 : STRING[20] = \"GRUNDPLATTE\"\n\
         \x20 V.L.VAR_1 : REAL = 23.45\n\
         \x20 V.L.VAR_2 : SGN08\n\
         \x20 V.L.B : BOOLEAN = TRUE\n\
         \x20 V.P.ARRAY_1[3][6] = [10,11,12,13,14,15, \\\n\
         \x20                      20,21,22,23,24,25, \\\n\
         \x20                      30,31,32,33,34,35 ]\n\
         \x20 V.L.ROW[3] = [10, 11, 12]\n\
         #ENDVAR\n\
         N10 #VAR\n\
         N20   V.S.EXAMPLE[5] = [1,2,3,4,5 ]\n\
         N30 #ENDVAR\n\
         G01 X[V.P.VAR_3] Y[V.P.ARRAY_1[1][2] + V.L.B] Z[V.L.ROW[2] + V.S.EXAMPLE[4] + V.L.VAR_1] F100\n\
         M30\n",
    );
    assert_eq!((r.position('X'), r.position('Y')), (10.0, 23.0));
    assert!(
        (r.position('Z') - 40.45).abs() < 1e-9,
        "{}",
        r.position('Z')
    );
    let d = parse_var_declaration("N5 V.L.N : UNS32 = 10").unwrap();
    assert_eq!(
        (d.ty, d.to_string().as_str()),
        (Some(VarType::Uns32), "V.L.N : UNS32=10")
    );
    let d = parse_var_declaration("V.P.T[2][2] = [1, 2, P1]").unwrap();
    assert_eq!(d.to_string(), "V.P.T[2][2]=[1, 2, P1]");
    // Refused where the fault stands, in check and in a run alike.
    for (decl, col) in [
        ("V.L.ROW[3] = [1, 2, 3, 4]", 24),
        ("V.L.S : STRING[127]", 15),
        ("V.L.X : FLOAT", 9),
        ("V.L.X = [1, 2]", 11),
    ] {
        fails_at(
            &rig,
            &format!("G01 X1 F100\n#VAR\n{decl}\n#ENDVAR\nM30\n"),
            20200,
            3,
            col,
            true,
        );
    }
    // A start value longer than the STRING[n] declared: the kernel's 21462 at its quote.
    fails_at(
        &rig,
        "G01 X1 F100\n#VAR\nV.L.S : STRING[5] = \"TOO LONG\"\n#ENDVAR\nM30\n",
        21462,
        3,
        21,
        true,
    );
    // A string variable keeps its string: used as a number it is 900008 at the word.
    fails_at(
        &rig,
        "#VAR\nV.L.S : STRING[5] = \"AB\"\n#ENDVAR\nG01 X[V.L.S] F100\nM30\n",
        900008,
        4,
        5,
        false,
    );
}

#[test]
fn string_variables_hold_compare_and_join_strings() {
    let rig = Rig::new();
    let r = runs_clean(
        &rig,
        "#VAR\n\
         \x20 V.L.NAME : STRING[20] = \"GRUNDPLATTE\"\n\
         \x20 V.L.EMPTY : STRING[5]\n\
         \x20 V.P.T : STRING[10] = \"abc\"\n\
         \x20 V.S.K : STRING[8]\n\
         \x20 V.L.ROW[2] : STRING[3] = \"x\"\n\
         #ENDVAR\n\
         $IF V.L.NAME == \"GRUNDPLATTE\"\n\
         G01 X1 F1000\n\
         $ENDIF\n\
         $IF V.L.NAME != \"grundplatte\" && LEN[V.L.EMPTY] == 0\n\
         G01 Y1 F1000\n\
         $ENDIF\n\
         V.L.EMPTY = \"ab\"\n\
         V.S.K = V.P.T + V.L.EMPTY\n\
         V.L.ROW[1] = LEFT[V.S.K, 2] + \"!\"\n\
         G01 X[LEN[V.S.K]] Y[IS_STRING[V.S.K] + 2 * EXIST[V.S.K] + 4 * IS_NUMBER[V.S.K]] \
         Z[FIND[V.L.NAME, \"PLATTE\"] + 10 * [V.L.ROW[1] == \"ab!\"] + 20 * [V.L.ROW[0] == \"x\"]]\n\
         M30\n",
    );
    assert_eq!(
        (r.position('X'), r.position('Y'), r.position('Z')),
        (5.0, 3.0, 36.0)
    );
    // An undeclared V. variable assigned a string becomes a string variable.
    let r = runs_clean(
        &rig,
        "V.L.NEW = \"abc\"\nG01 X[IS_STRING[V.L.NEW] + LEN[V.L.NEW]] F1000\nM30\n",
    );
    assert_eq!(r.position('X'), 4.0);
    // A string variable passed as a cycle parameter is a string parameter.
    rig.program(
        "c.cyc",
        "G01 X[IS_STRING[@P1] + 2 * [@P1 == \"abc\"]] Y[@P2] F1000\nM17\n",
    );
    let r = runs_clean(
        &rig,
        "#VAR\nV.L.S : STRING[5] = \"abc\"\n#ENDVAR\nL CYCLE [NAME=c.cyc @P1=V.L.S @P2=LEN[V.L.S]]\nM30\n",
    );
    assert_eq!((r.position('X'), r.position('Y')), (3.0, 3.0));
    // Printed back, a declaration and a string expression parse to the same.
    let d = parse_var_declaration("V.L.S : STRING[5] = \"ab c\"").unwrap();
    assert_eq!(d.to_string(), "V.L.S : STRING[5]=\"ab c\"");
    assert_eq!(parse_var_declaration(&d.to_string()).unwrap(), d);
    let b = parse_block("V.L.S = MID[V.L.T + \"x\", 2, 1]").unwrap();
    assert_eq!(b.to_string(), "V.L.S=MID[V.L.T + \"x\", 2, 1]");
    assert_eq!(parse_block(&b.to_string()).unwrap(), b);
}

#[test]
fn string_errors_are_the_kernels_at_their_place() {
    let rig = Rig::new();
    let decl = "#VAR\nV.L.S : STRING[3] = \"ab\"\nV.L.N = 1\n#ENDVAR\n";
    // Longer than the variable holds: 21462 at the assignment.
    fails_at(
        &rig,
        &format!("{decl}V.L.S = \"abcd\"\nM30\n"),
        21462,
        5,
        1,
        false,
    );
    fails_at(
        &rig,
        &format!("{decl}G01 X1 F100 V.L.S = V.L.S + \"cd\"\nM30\n"),
        21462,
        5,
        13,
        false,
    );
    // A number into a STRING variable, a string into a number.
    fails_at(
        &rig,
        &format!("{decl}V.L.S = 5\nM30\n"),
        900009,
        5,
        1,
        false,
    );
    fails_at(
        &rig,
        &format!("{decl}V.L.N = V.L.S\nM30\n"),
        900008,
        5,
        1,
        false,
    );
    fails_at(
        &rig,
        &format!("{decl}P1 = V.L.S\nM30\n"),
        900008,
        5,
        1,
        false,
    );
    // An operator strings do not take: 21458.
    fails_at(
        &rig,
        &format!("{decl}G01 X[V.L.S * 2] F100\nM30\n"),
        21458,
        5,
        5,
        false,
    );
    fails_at(
        &rig,
        &format!("{decl}G01 X[V.L.S + 1] F100\nM30\n"),
        21458,
        5,
        5,
        false,
    );
    // A position outside the string: 21545.
    fails_at(
        &rig,
        &format!("{decl}V.L.S = DELETE[\"Hello world!\", 7, 100]\nM30\n"),
        21545,
        5,
        1,
        false,
    );
    // A literal longer than 126 characters: 21870 at its quote, in check too.
    let long = "y".repeat(127);
    fails_at(
        &rig,
        &format!("G01 X1 F100\nV.L.S = \"{long}\"\nM30\n"),
        21870,
        2,
        9,
        true,
    );
    // Joined beyond 126 characters: 21870 where it is joined.
    let half = "z".repeat(100);
    fails_at(
        &rig,
        &format!("V.L.A = \"{half}\"\nV.L.B = V.L.A + V.L.A\nM30\n"),
        21870,
        2,
        1,
        false,
    );
}

#[test]
fn ncchannel_check_names_the_line_of_an_error_in_a_continued_block() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.nc");
    std::fs::write(
        &bad,
        "% 100 (title)\r\nN10 G01 F1000 \\\r\nN20 X10 Q5\r\nM30\r\n",
    )
    .unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .arg("check")
        .arg(&bad)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{text}");
    let want = format!("{}:3:9: error 20200: ", bad.display());
    assert!(text.contains(&want), "{text}");
    assert!(text.contains("  N20 X10 Q5\n          ^"), "{text}");
}

#[test]
fn exist_is_number_and_is_string_ask_about_a_variable() {
    let rig = Rig::new();
    // EXIST: defined or not, without an error for the undefined one.
    let r = runs_clean(
        &rig,
        "P1 = 5\nV.L.A = 2\n\
         G01 X[EXIST[P1]] Y[EXIST[P2] + 2] Z[EXIST[V.L.A] + EXIST[V.P.NONE] * 10] F1000\nM30\n",
    );
    assert_eq!(
        (r.position('X'), r.position('Y'), r.position('Z')),
        (1.0, 2.0, 1.0)
    );
    // IS_NUMBER / IS_STRING of numbers, in conditions as ISG's editor test programs write them.
    let r = runs_clean(
        &rig,
        "P1 = 5\n$IF IS_NUMBER[P1] == TRUE\nG01 X3 F1000\n$ENDIF\n\
         $IF is_string[P1] == TRUE\nG01 Y3 F1000\n$ENDIF\nG01 Z[IS_NUMBER[P7]] F1000\nM30\n",
    );
    assert_eq!(
        (r.position('X'), r.position('Y'), r.position('Z')),
        (3.0, 0.0, 0.0)
    );
    // The argument is one variable, not an expression (20200 at the argument).
    fails_at(&rig, "G01 X[EXIST[3]] F100\nM30\n", 20200, 1, 13, true);
    fails_at(&rig, "G01 X[IS_NUMBER P1] F100\nM30\n", 20200, 1, 17, true);
    // An index of the variable is still evaluated: an undefined one is an error.
    fails_at(&rig, "G01 X[EXIST[P[P9]]] F100\nM30\n", 900005, 1, 5, false);
}

#[test]
fn cycle_parameters_may_be_strings() {
    let rig = Rig::new();
    rig.program(
        "c.cyc",
        "$IF IS_STRING[@P1] == TRUE\nG01 X1 F1000\n$ENDIF\n\
         $IF IS_NUMBER[@P2] == TRUE\nG01 Y[@P2] F1000\n$ENDIF\n\
         G01 Z[EXIST[@P1] + EXIST[@P3] * 10 + IS_NUMBER[@P1] * 100] F1000\nM17\n",
    );
    // The form of ISG's editor test programs: a blank before `=`, a quoted string.
    let r = runs_clean(
        &rig,
        "L CYCLE [NAME=c.cyc @P1 =\"String1\" @P2=12.34]\nM30\n",
    );
    assert_eq!(
        (r.position('X'), r.position('Y'), r.position('Z')),
        (1.0, 12.34, 1.0)
    );
    // A string with blanks and a semicolon inside its quotes.
    let r = runs_clean(&rig, "L CYCLE [NAME=c.cyc @P1=\"a b; c\" @P2=1]\nM30\n");
    assert_eq!(r.position('X'), 1.0);
    // Used as a number, a string parameter is 900008 where it is used.
    rig.program("s.cyc", "G01 X[@P1] F100\nM17\n");
    rig.program("main.nc", "L CYCLE [NAME=s.cyc @P1=\"abc\"]\nM30\n");
    let r = rig.run("main.nc", None, 1_000_000);
    assert_eq!(r.finish, Some(Finish::Error), "{}", r.log);
    assert_eq!(r.error_codes(), [900008], "{}", r.log);
    // A string without its closing quote is 20200 at the quote.
    fails_at(
        &rig,
        "L CYCLE [NAME=c.cyc @P1=\"abc]\nM30\n",
        20200,
        1,
        25,
        true,
    );
    let b = parse_block("L CYCLE [NAME=c.cyc @P1 = \"x y\" @P2=2]").unwrap();
    assert_eq!(b.to_string(), "L CYCLE [NAME=c.cyc @P1=\"x y\" @P2=2]");
}

#[test]
fn ll_cycle_calls_a_local_subroutine_with_parameters() {
    let rig = Rig::new();
    let text = "%L UP1\nG01 X[@P1] F1000\n$IF IS_STRING[@P2] == TRUE\nG01 Y5\n$ENDIF\nM17\n\
                %main\nLL CYCLE [NAME=UP1 @P1=7 @P2=\"text\"]\nG01 Z2\nM30\n";
    assert_eq!(check_places(text), [], "check");
    rig.program("t.nc", text);
    let r = rig.run("t.nc", None, 1_000_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    assert_eq!(
        (r.position('X'), r.position('Y'), r.position('Z')),
        (7.0, 5.0, 2.0)
    );
    // A modal call is refused by name (900133) at MODAL.
    fails_at(
        &rig,
        "L CYCLE [NAME=c.cyc MODAL_MOVE @P1=1]\nM30\n",
        900133,
        1,
        21,
        true,
    );
    let b = parse_block("LL CYCLE [NAME=UP1 @P1=7]").unwrap();
    assert_eq!(b.to_string(), "LL CYCLE [NAME=UP1 @P1=7]");
    // Streamed, a local call is refused as `LL name` is (21479).
    let s = rig.run(
        "streaming.nc",
        Some(feeder("LL CYCLE [NAME=UP1 @P1=7]\nM30\n", 992, 1)),
        1_000_000,
    );
    assert_eq!(s.finish, Some(Finish::Error), "{}", s.log);
    assert_eq!(s.error_codes(), [21479], "{}", s.log);
    // A name without its %L section is 20373, as for LL.
    rig.program("n.nc", "LL CYCLE [NAME=NOPE]\nM30\n");
    let r = rig.run("n.nc", None, 1_000_000);
    assert_eq!(r.error_codes(), [20373], "{}", r.log);
}

#[test]
fn pp_is_the_parameter_whose_number_a_parameter_holds() {
    let rig = Rig::new();
    // TF5200 programming manual, "Indirect parameters": P1 = 20, PP1 = 5 sets P20.
    let r = runs_clean(
        &rig,
        "P1 = 20  P2 = 40\nPP1 = 5\nPP2 = PP1 + 1\nP3 = 1\n\
         G01 X[P20] YP40 ZPPP3+2 F1000\nM30\n",
    );
    assert_eq!(
        (r.position('X'), r.position('Y'), r.position('Z')),
        (5.0, 6.0, 7.0)
    );
    let b = parse_block("PP1 = PPP2").unwrap();
    assert_eq!(b.to_string(), "P[P1]=P[P[P2]]");
    // P1 undefined: PP1 has no number.
    fails_at(&rig, "G01 X[PP1] F100\nM30\n", 900005, 1, 5, false);
    // Each P of a chain is a bracket when printed (`P[P[…]]`): a chain deeper than a
    // bracket nesting may be is refused as that nesting would be, so every block read prints
    // to a text that reads back.
    let deep = format!("$IF {}1 >= 1", "P".repeat(80));
    let e = parse_block(&deep).unwrap_err();
    assert_eq!(
        (e.code, e.message.as_str()),
        (20200, "expression nested too deeply")
    );
    let ok = format!("$IF {}1 >= 1", "P".repeat(40));
    let b = parse_block(&ok).unwrap();
    assert_eq!(
        parse_block(&b.to_string()).unwrap().to_string(),
        b.to_string()
    );
}

#[test]
fn v_a_abs_is_the_axis_position_after_the_previous_block() {
    let rig = Rig::new();
    // TF5200 programming manual, "Axis-specific variables (V.A.)": V.A.ABS.X or V.A.ABS[0].
    let r = runs_clean(
        &rig,
        "G01 X10 Y20 F1000\nG01 X[V.A.ABS.X + 1] YV.A.ABS[1]+2\n\
         G92 X0\nG01 Z[V.A.ABS.X + 3]\nM30\n",
    );
    assert_eq!(
        (r.position('X'), r.position('Y'), r.position('Z')),
        (11.0, 22.0, 3.0)
    );
    let b = parse_block("X[v.a.abs.x] Y[V.A.ABS[P1 + 1]]").unwrap();
    assert_eq!(b.to_string(), "X[V.A.ABS.X] Y[V.A.ABS[P1 + 1]]");
    // The other V.A. fields are refused by name; V.A. is read-only.
    fails_at(&rig, "G01 X[V.A.PROG.X] F100\nM30\n", 900133, 1, 11, true);
    fails_at(&rig, "V.A.ABS.X = 5\nM30\n", 20200, 1, 1, true);
    // An axis the channel does not have has no position.
    fails_at(&rig, "G01 X[V.A.ABS.U] F100\nM30\n", 900005, 1, 5, false);
    fails_at(&rig, "G01 X[V.A.ABS[3]] F100\nM30\n", 900005, 1, 5, false);
}

#[test]
fn hsc_options_and_file_names() {
    let rig = Rig::new();
    // TF5200 programming manual, "Trim a contour (#HSC ON/OFF)": options after ON, or
    // parameters alone.
    let r = runs_clean(
        &rig,
        "#HSC ON [BSPLINE PATH_DEV 0.2 TRACK_DEV 5 MERGE 1]\nG01 X10 F1000\n#HSC OFF\n\
         #HSC [OPMODE 1 CONTERROR 0.01]\nG01 Y5\nM30\n",
    );
    assert_eq!((r.position('X'), r.position('Y')), (10.0, 5.0));
    let b = parse_block("#HSC [BSPLINE PATH_DEV=0.2]").unwrap();
    assert_eq!(b.to_string(), "#HSC [BSPLINE PATH_DEV=0.2]");
    // "Definition von Dateinamen (#FILE NAME)": MSG names the #MSG SAVE file, inert here.
    let r = runs_clean(
        &rig,
        "#FILENAME[ MSG=\"prog_flow.txt\" ]\n#FILE NAME [MSG \"x.txt\"]\nG01 X2 F1000\nM30\n",
    );
    assert_eq!(r.position('X'), 2.0);
    assert_eq!(
        parse_block("#FILENAME [MSG=\"a.txt\"] (c)")
            .unwrap()
            .to_string(),
        "#FILENAME [MSG=\"a.txt\"] (c)".split(" (").next().unwrap()
    );
    // Renaming an implicit subroutine is refused by name at its id.
    fails_at(
        &rig,
        "#FILENAME [M6=\"tool.nc\"]\nM30\n",
        900133,
        1,
        12,
        true,
    );
    fails_at(&rig, "#FILENAME [XY=\"a\"]\nM30\n", 20200, 1, 12, true);
    fails_at(&rig, "#FILENAME [MSG=\"a]\nM30\n", 20200, 1, 16, true);
}

#[test]
fn v_g_tool_radii_come_from_the_tool_list() {
    let rig = Rig::new();
    let params = rig.startup().parent().unwrap().to_path_buf();
    std::fs::write(
        params.join("tools.lis"),
        "wz[1].radius 50000\nwz[2].radius 25000\n",
    )
    .unwrap();
    // TF5200 programming manual, "Global variables (V.G.)": WZ_AKT the active tool, WZ[j]
    // any tool data set; D0 (none selected) has radius 0.
    let r = runs_clean(
        &rig,
        "G01 X[V.G.WZ[2].R] Y[V.G.WZ_AKT.R + 1] F1000\nD1\nG01 Z[V.G.WZ_AKT.R]\nM30\n",
    );
    assert_eq!(
        (r.position('X'), r.position('Y'), r.position('Z')),
        (2.5, 1.0, 5.0)
    );
    let b = parse_block("X[v.g.wz_akt.r] Y[V.G.WZ[P1].R]").unwrap();
    assert_eq!(b.to_string(), "X[V.G.WZ_AKT.R] Y[V.G.WZ[P1].R]");
    // A D the tool list does not have; variables and fields not modelled; read-only.
    fails_at(&rig, "G01 X[V.G.WZ[3].R] F100\nM30\n", 900005, 1, 5, false);
    fails_at(&rig, "G01 X[V.G.FEEDRATE] F100\nM30\n", 900133, 1, 11, true);
    fails_at(
        &rig,
        "G01 X[V.G.WZ_AKT.KIN_ID] F100\nM30\n",
        900133,
        1,
        18,
        true,
    );
    // The other fields of the tool list and the zero-offset groups print back as written.
    let b =
        parse_block("X[v.g.wz_akt.l] Y[V.G.WZ[2].ok] Z[V.G.WZ[P1].V[2] + V.G.NP[1].V.x]").unwrap();
    assert_eq!(
        b.to_string(),
        "X[V.G.WZ_AKT.L] Y[V.G.WZ[2].OK] Z[V.G.WZ[P1].V[2] + V.G.NP[1].V.X]"
    );
    fails_at(&rig, "V.G.WZ[1].R = 2\nM30\n", 20200, 1, 1, true);
}

#[test]
fn a_comment_block_may_stand_among_var_declarations() {
    // ISG's editor documents a variable with a comment block inside `#VAR`
    // (`isg-stuttgart/vscode-isg-cnc`, `src/test/res/docHover1.nc`).
    let rig = Rig::new();
    let r = runs_clean(
        &rig,
        "#VAR\n\
         #COMMENT BEGIN\n\
         \x20 First doc for V.P.VAR_1, not NC: X = = ]\n\
         #COMMENT END\n\
         \x20 V.P.VAR_1 = 10 ; doc\n\
         #ENDVAR\n\
         G01 XV.P.VAR_1 F100\n\
         M30\n",
    );
    assert_eq!(r.position('X'), 10.0);
    // Inside the comment `#ENDVAR` is comment text: both blocks stay open to the end (20375).
    assert_eq!(
        check_places("#VAR\n#COMMENT BEGIN\n#ENDVAR\nM30\n"),
        [(1, 1, 20375), (2, 1, 20375)],
    );
}

/// A runtime.toml whose axes are named `X1`, `Y` and `A1`.
fn named_axes_rig() -> Rig {
    let axis = |name: &str| {
        format!(
            "[[axes]]\nname = \"{name}\"\nmax_velocity_mm_per_min = 30000.0\n\
             max_acceleration_mm_per_s2 = 2000.0\nrapid_mm_per_min = 30000.0\n"
        )
    };
    Rig::with_runtime(&format!("{}{}{}", axis("X1"), axis("Y"), axis("A1")))
}

#[test]
fn axes_named_with_digits_take_an_equals_sign() {
    let rig = named_axes_rig();
    let r = runs_clean(
        &rig,
        "P1 = 2\nG01 X1=10 Y5 F1000\nX1 = P1 + 12 A1=90\nG01 X1=P1*3 F1000\nM30\n",
    );
    assert_eq!(
        r.machine.channels()[0]
            .report()
            .named_positions
            .into_iter()
            .map(|(n, v)| (n.to_string(), v))
            .collect::<Vec<_>>(),
        [
            ("X1".to_string(), 6.0),
            ("Y".to_string(), 5.0),
            ("A1".to_string(), 90.0)
        ]
    );
    // Printed back, a named axis parses to the same block.
    let b = parse_block("G01 X1 = P1 + 2 Y5").unwrap();
    assert_eq!(b.to_string(), "G1 X1=P1 + 2 Y5");
    assert_eq!(
        parse_block(&b.to_string()).unwrap().to_string(),
        b.to_string()
    );
    // Without `=`, X10 is X with 10 — and this channel's X axis is X1: X alone is no axis.
    fails_at(&rig, "G01 X10 F1000\nM30\n", 20200, 1, 5, false);
    // A name the channel does not have, and one named twice.
    fails_at(&rig, "G01 Z1=5 F1000\nM30\n", 20200, 1, 5, false);
    fails_at(&rig, "G01 X1=5 X1=6 F1000\nM30\n", 20203, 1, 10, false);
    // Too long a name is 20200 at the name, in check too.
    fails_at(
        &rig,
        "G01 X123456789012345678=5 F1000\nM30\n",
        20200,
        1,
        5,
        true,
    );
    // An ordinary channel: `X1=5` names an axis it does not have.
    fails_at(&Rig::new(), "G01 X1=5 F1000\nM30\n", 20200, 1, 5, false);
}

#[test]
fn a_skipped_branch_runs_nothing_of_its_lines_and_a_streamed_ll_in_it_is_still_refused() {
    let rig = Rig::new();
    // The false branch holds a line that would not parse and a `$` inside a comment; the
    // nested `$IF` in it keeps the structure right. Neither runs, as the kernel skips them.
    let text = "P1=1\n$IF P1 == 2\nG01 X*** F\n( cost in $ )\n$IF P1 == 1\nG01 Y5 F100\n\
                $ENDIF\n$ELSE\nG01 X1 F100\n$ENDIF\nM30\n";
    let r = runs_clean_unchecked(&rig, text);
    assert_eq!((r.position('X'), r.position('Y')), (1.0, 0.0));
    // A stream refuses an LL call even in a branch it skips (the kernel's 21479), as a
    // file runs it only when it is taken.
    let s = rig.run(
        "streaming.nc",
        Some(feeder("P1=1\n$IF P1 == 2\nLL SUB1\n$ENDIF\nM30\n", 992, 1)),
        100_000,
    );
    assert_eq!(s.error_codes(), vec![21479], "{}", s.log);
}

/// A program that must run to its end in a file and streamed (`check` is not asked: the
/// program may hold lines only a skip makes harmless).
fn runs_clean_unchecked(rig: &Rig, text: &str) -> RunResult {
    let r = run_everywhere(rig, text);
    assert_eq!(r.finish, Some(Finish::Ended), "{text}\n{}", r.log);
    r
}

/// V.E. structure members (TF5200 External variables) and `#FILENAME [MSG=V.E.x]` (TF5200
/// programming manual, "Definition of file names"), which were 20200: they parse, and print
/// back as text that parses to the same block.
#[test]
fn external_variable_members_and_filename_from_a_variable_parse() {
    for line in [
        "V.E.UserInteraction.Message = \"Insert tool\"",
        "V.E.Sch.Preflow = 3",
        "V.E.INFO[1].X = V.E.INFO[0].X + V.E.A.B.C[2]",
        "#FILENAME [MSG=V.E.TEACH_FILE_NAME]",
        "#FILE NAME [MSG = V.E.teach_file_name]",
    ] {
        let b = parse_block(line).unwrap_or_else(|e| panic!("{line}: {e}"));
        assert_eq!(parse_block(&b.to_string()).unwrap(), b, "{line}");
    }
    let b = parse_block("V.E.INFO[1].X = 2").unwrap();
    assert_eq!(
        b.to_string(),
        "V.E.INFO.X[1]=2",
        "the members joined, then the index"
    );
    // Members are V.E.'s: V.P.A.B stays a syntax error, and a member needs a name.
    for line in ["V.P.A.B = 1", "V.E.A.[1] = 1"] {
        assert_eq!(parse_block(line).unwrap_err().code, 20200, "{line}");
    }
}
