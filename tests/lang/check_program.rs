//! The program checker: every nc/ file clean, each structure error number at the right place,
//! and `ncchannel check` through the binary.

use std::path::Path;
use std::process::Command as Process;

use ncchannel::lang::*;
use ncchannel::vocab::flush::FlushKind;

fn codes(text: &str) -> Vec<(usize, usize, u32)> {
    check_program(text)
        .into_iter()
        .map(|d| (d.line, d.col, d.code))
        .collect()
}

fn nc_files() -> Vec<std::path::PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("nc");
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e != "md"))
        .collect();
    v.sort();
    v
}

#[test]
fn every_nc_file_parses_and_checks_clean() {
    let files = nc_files();
    assert!(files.len() >= 14, "{files:?}");
    for path in files {
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(check_program(&text), vec![], "{}", path.display());
        // And every line outside #COMMENT blocks parses on its own, CR LF or not.
        let mut in_comment = false;
        for line in text.lines() {
            if in_comment {
                in_comment = !is_comment_end(line);
                continue;
            }
            let b = parse_block(&format!("{line}\r\n")).unwrap();
            in_comment = b.body == Body::Command(Box::new(Command::CommentBegin));
        }
    }
}

#[test]
fn streaming_program_is_virtual() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("nc");
    assert!(!dir.join("streaming.nc").exists());
    let demo = std::fs::read_to_string(dir.join("demo.nc")).unwrap();
    let blocks: Vec<Block> = demo.lines().map(|l| parse_block(l).unwrap()).collect();
    let has = |f: &dyn Fn(&Body) -> bool| blocks.iter().any(|b| f(&b.body));
    assert!(has(&|b| matches!(
        b,
        Body::Command(c) if **c == Command::Flush(FlushKind::Continue)
    )));
    assert!(has(
        &|b| matches!(b, Body::Control(c) if matches!(**c, Control::If(_)))
    ));
    // Streamable: no loops, no backward jumps.
    assert!(!has(&|b| matches!(
        b,
        Body::Control(c) if matches!(
            **c,
            Control::For { .. } | Control::While(_) | Control::Do | Control::Repeat
        )
    )));
    let g_codes: Vec<f64> = blocks
        .iter()
        .filter_map(|b| match &b.body {
            Body::Items(items) => Some(items),
            _ => None,
        })
        .flatten()
        .filter_map(|i| match i {
            Item::Word(Word {
                letter: b'G',
                value: Value::Num(v),
                ..
            }) => Some(*v),
            _ => None,
        })
        .collect();
    for g in [0.0, 1.0, 2.0, 3.0] {
        assert!(g_codes.contains(&g), "G{g}");
    }
    // More than the stream buffer holds, so the demo meets a full buffer (11012).
    assert!(demo.len() > 4094, "{} bytes", demo.len());
    assert!(demo.lines().any(|l| l.contains("M30")));
}

#[test]
fn stray_control_statements_have_their_own_numbers() {
    let cases = [
        ("$ELSE", 20214),
        ("$ELSEIF P1", 20216),
        ("$ENDIF", 20218),
        ("$CASE 1", 20221),
        ("$DEFAULT", 20223),
        ("$BREAK", 20243),
        ("$ENDSWITCH", 20225),
        ("$ENDFOR", 20232),
        ("$ENDWHILE", 20237),
        ("$ENDDO P1", 20240),
        ("$UNTIL P1", 21469),
        ("$CONTINUE", 20244),
    ];
    for (stmt, code) in cases {
        let text = format!("N10 G1 X1\nN20 {stmt}\nM30\n");
        assert_eq!(codes(&text), vec![(2, 5, code)], "{stmt}");
    }
    // Mismatched closers are stray too, and the opener stays open.
    assert_eq!(codes("$IF P1\n$ENDFOR\n$ENDIF\n"), vec![(2, 1, 20232)]);
    assert_eq!(codes("$IF P1\n$ELSE\n$ELSE\n$ENDIF\n"), vec![(3, 1, 20214)]);
    assert_eq!(
        codes("$IF P1\n$ELSE\n$ELSEIF P2\n$ENDIF\n"),
        vec![(3, 1, 20216)]
    );
}

/// Words after the condition of `$CASE`, `$ENDDO` or `$UNTIL` (TF5200 diagnosis IDs 20222,
/// 20241, 21470 "After '…' only the condition is permissible.") and a `$ELSEIF` without its
/// condition (ID 20216, "incomplete syntax"), at the offending word, in `check` and in a run
/// — also where the run skips the line (a `$CASE` that does not match, a false `$IF`).
#[test]
fn words_after_a_control_condition_have_the_kernels_ids() {
    let cases = [
        (
            "$SWITCH 5\n$CASE 5 G01 X100 F100\n$BREAK\n$ENDSWITCH",
            2,
            9,
            20222,
        ),
        (
            "$SWITCH 5\n$CASE 4 G01 X100 F100\n$BREAK\n$ENDSWITCH",
            2,
            9,
            20222,
        ),
        ("P2=10\n$DO\n$ENDDO P2 >= 10 G01 X100 F1000", 3, 17, 20241),
        ("$REPEAT\n$UNTIL P2 > 20 G01 X100 F1000", 2, 16, 21470),
        ("$IF 0\n$ELSEIF\n$ENDIF", 2, 1, 20216),
        ("$ELSEIF", 1, 1, 20216),
    ];
    let rig = crate::support::Rig::new();
    for (prog, line, col, code) in cases {
        let text = format!("{prog}\nM30\n");
        // (`check` also lists the `$DO` the refused `$ENDDO` leaves open.)
        assert!(codes(&text).contains(&(line, col, code)), "{prog}");
        rig.program("ctl.nc", &text);
        let r = rig.run("ctl.nc", None, 100_000);
        assert_eq!(r.error_codes(), [u64::from(code)], "{prog}: {}", r.log);
        assert_eq!(
            r.of("error")[0]["line"].as_u64(),
            Some(line as u64),
            "{prog}"
        );
    }
}

#[test]
fn well_formed_structures_pass() {
    let text = "\
%L SUB
$FOR P1 = 1, 3
  $IF P1 == 2
    $CONTINUE
  $ELSEIF P1 == 3
    $BREAK
  $ELSE
    G1 X[P1]
  $ENDIF
$ENDFOR
M17
%main
#VAR
  V.L.COUNT = 3

  V.P.TABLE[4] ; four entries
#ENDVAR
$SWITCH V.L.COUNT
$CASE 1
  $WHILE P2 < 3
    P2 = P2 + 1
  $ENDWHILE
$BREAK
$DEFAULT
  $DO
  $ENDDO P2 > 5
  $REPEAT
  $UNTIL 1
$ENDSWITCH
$IF 1 $GOTO [END]
[END] LL SUB
#COMMENT BEGIN
this is ( not NC $ENDIF
#comment end
M30
";
    assert_eq!(check_program(text), vec![]);
}

#[test]
fn open_blocks_at_program_end() {
    assert_eq!(
        codes("N10 $IF P1\nN20 $WHILE 1\nM30\n"),
        vec![(1, 5, 20375), (2, 5, 20375)]
    );
    // Each program level closes its own blocks.
    assert_eq!(
        codes("%L SUB\n$SWITCH P1\nM17\n%main\n$ENDSWITCH\nM30\n"),
        vec![(2, 1, 20375), (5, 1, 20225)]
    );
    assert_eq!(codes("#VAR\nV.L.X = 1\n"), vec![(1, 1, 20375)]);
    assert_eq!(codes("G1 X1\n#COMMENT BEGIN\nM30\n"), vec![(2, 1, 20375)]);
}

#[test]
fn labels_and_jumps() {
    assert_eq!(codes("N40: X1\nN50 X2\nN40: X3\n"), vec![(3, 1, 20836)]);
    assert_eq!(codes("[A] X1\n[a] X3\n"), vec![(2, 1, 20836)]);
    assert_eq!(codes("$GOTO N40\nN30 X1\nM30\n"), vec![(1, 1, 20840)]);
    assert_eq!(
        codes("N10 $IF P1 == 1 $GOTO [LATER]\nM30\n"),
        vec![(1, 17, 20840)]
    );
    // A plain block number is no label; the message says so.
    let d = check_program("$GOTO N40\nN40 X1\n");
    assert_eq!(d[0].code, 20840);
    assert!(d[0].message.contains("N40:"), "{}", d[0].message);
    // Backward and forward jumps both resolve in a file.
    assert_eq!(
        codes("N10: X1\n$GOTO N10\n$GOTO [FWD]\n[FWD] M30\n"),
        vec![]
    );
    // Labels are per program level.
    assert_eq!(
        codes("%L SUB\n[A] M17\n%main\n$GOTO [A]\nM30\n"),
        vec![(4, 1, 20840)]
    );
}

#[test]
fn syntax_errors_inside_var_and_program() {
    assert_eq!(
        codes("#VAR\nV.L.A = \nV.E.B\n#ENDVAR\n"),
        vec![(2, 9, 20200), (3, 1, 20200)]
    );
    assert_eq!(codes("#ENDVAR\n"), vec![(1, 1, 20200)]);
    assert_eq!(
        codes("G1 X1\nG1 M70000\n#CACHE LOAD\n"),
        vec![(2, 4, 20157), (3, 12, 21560)]
    );
}

fn run_check(args: &[&Path]) -> (i32, String) {
    let out = Process::new(env!("CARGO_BIN_EXE_ncchannel"))
        .arg("check")
        .args(args)
        .output()
        .unwrap();
    let mut text = String::from_utf8_lossy(&out.stdout).into_owned();
    text.push_str(&String::from_utf8_lossy(&out.stderr));
    (out.status.code().unwrap(), text)
}

#[test]
fn cli_check_clean_files_exit_zero() {
    let nc = Path::new(env!("CARGO_MANIFEST_DIR")).join("nc");
    let (code, out) = run_check(&[&nc]);
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("0 error(s)"), "{out}");
    let demo = nc.join("demo.nc");
    let cyc = nc.join("Laser_on.cyc");
    assert_eq!(run_check(&[&demo, &cyc]).0, 0);
}

#[test]
fn cli_check_broken_file_reports_position_and_caret() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.nc");
    std::fs::write(&bad, "N10 G1 X10\r\nN20 G999 X1\r\nM30\r\n").unwrap();
    let (code, out) = run_check(&[&bad]);
    assert_eq!(code, 1, "{out}");
    let want = format!(
        "{}:2:5: error 20131: unknown G function G999\n  N20 G999 X1\n      ^",
        bad.display()
    );
    assert!(out.contains(&want), "{out}");

    let missing = dir.path().join("missing.nc");
    let (code, out) = run_check(&[&missing]);
    assert_eq!(code, 1);
    assert!(out.contains("missing.nc"), "{out}");
}

/// `ncchannel check FILE` and `ncchannel run FILE` from the clone's root, with the start-up
/// list both read by default: (check's exit code and output, run's output).
fn check_and_run(file: &Path) -> ((i32, String), String) {
    let cmd = |what: &str| {
        let out = Process::new(env!("CARGO_BIN_EXE_ncchannel"))
            .arg(what)
            .arg(file)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .env_remove("NCCHANNEL_PARAMS")
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout).into_owned()
            + &String::from_utf8_lossy(&out.stderr);
        (out.status.code().unwrap(), text)
    };
    (cmd("check"), cmd("run").1)
}

/// A negative literal dwell: `run` refuses it with 20752 (G04) or 20751 (#TIME) when it
/// decodes the block; `check` finds it with the same id, at the time's word.
#[test]
fn check_refuses_negative_dwells_with_runs_ids() {
    assert_eq!(codes("N10 G04 X-1\n"), [(1, 9, 20752)]);
    assert_eq!(codes("N10 G04 -0.5\n"), [(1, 5, 20752)]);
    assert_eq!(codes("N10 #TIME -2\n"), [(1, 5, 20751)]);
    // Not negative, or known only when it runs: nothing to say.
    assert_eq!(
        codes("G04 X0.5\nG04 2\n#TIME 1\nG04 X[P1]\n#TIME P1\nG01 X-1\n"),
        []
    );
    let dir = tempfile::tempdir().unwrap();
    for (text, id, col) in [("G04 X-1\nM30\n", 20752, 5), ("#TIME -2\nM30\n", 20751, 1)] {
        let f = dir.path().join("dwell.nc");
        std::fs::write(&f, text).unwrap();
        let ((code, check), run) = check_and_run(&f);
        assert_eq!(code, 1, "{check}");
        assert!(
            check.contains(&format!("dwell.nc:1:{col}: error {id}: dwell time -")),
            "{check}"
        );
        assert!(run.contains(&format!("error {id}: dwell time -")), "{run}");
    }
}

/// An end point outside the software limits at the program's start (absolute, no offsets):
/// `run` refuses it with 21897 before the axis moves; `check` finds it with the same id and
/// text, at the axis word, against the limits of the start-up list `run` reads.
#[test]
fn check_refuses_a_start_position_outside_the_soft_limits_as_run_does() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("start.nc");
    std::fs::write(&f, "%start\nN10 G90 G00 X5000 Y10\nN20 G91 X5000\nM30\n").unwrap();
    let ((code, check), run) = check_and_run(&f);
    let text = "error 21897: axis X end point 5000 mm, above the upper software limit (limits -1000 to 1000 mm)";
    assert_eq!(code, 1, "{check}");
    assert!(check.contains(&format!("start.nc:2:13: {text}")), "{check}");
    assert!(run.contains(text), "{run}");
    // After G91 the frame is the program's business: nothing more is said (one error).
    assert!(check.contains("1 error(s)"), "{check}");
    // Inside the limits: clean.
    std::fs::write(&f, "N10 G00 X500 Y-999.5\nM30\n").unwrap();
    let ((code, check), _) = check_and_run(&f);
    assert_eq!(code, 0, "{check}");
}
