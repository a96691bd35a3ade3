//! Constructs of real ISG programs (TF5200 programming manual; the test programs of ISG's
//! editor support `isg-stuttgart/vscode-isg-cnc`, `src/test/res/*.nc`): each one run from a
//! file and streamed — whole and one line per packet — with `check` agreeing with the run.

mod common;

use common::{feeder, Rig, RunResult};
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
        assert_eq!(s.block_texts(), file.block_texts(), "{how}: {text}");
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
        let Body::ProgramHead {
            name: n, title: t, ..
        } = &b.body
        else {
            panic!("{line}: {b:?}")
        };
        assert_eq!((n.as_str(), t.as_str()), (name, title), "{line}");
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
