//! What a streamed program may and may not do (ISG FCT-C19 Data streaming §2.3), compared with the same
//! program run from a file, under every packetisation.

use crate::support as common;

use std::time::Duration;

use common::{feeder, Rig};
use ncchannel::channel::Finish;
use ncchannel::machine::Op;
use ncchannel::SearchTarget;

const EXAMPLES: [&str; 6] = [
    "switchstream.nc",
    "commentstream.nc",
    "goto_forward.nc",
    "streaming_spline.nc",
    "flush_continue.nc",
    "subroutine_call.nc",
];

fn repo_nc(name: &str) -> String {
    std::fs::read_to_string(format!("{}/nc/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

/// A rig with every shipped program in its nc/ folder.
fn rig() -> Rig {
    let rig = Rig::new();
    for e in std::fs::read_dir(format!("{}/nc", env!("CARGO_MANIFEST_DIR"))).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), rig.nc().join(e.file_name())).unwrap();
    }
    rig
}

/// The document's packets (blank-line separated in nc/) as feeder input: each packet ends with
/// a form feed and a pause, so the channel has decoded a packet before the next arrives.
fn document_packets(text: &str, pause: u64) -> String {
    text.lines()
        .map(|l| {
            if l.trim().is_empty() {
                format!("\x0c {pause}\n")
            } else {
                format!("{l}\n")
            }
        })
        .collect()
}

fn line_per_packet(text: &str) -> String {
    text.lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| format!("{l}\n\x0c 3\n"))
        .collect()
}

#[test]
fn seed_examples_execute_the_same_blocks_from_file_and_from_any_packetisation() {
    let rig = rig();
    for name in EXAMPLES {
        let text = repo_nc(name);
        let file = rig.run(name, None, 5_000_000);
        assert_eq!(
            file.finish,
            Some(Finish::Ended),
            "{name} from file: {:?}",
            file.of("error")
        );
        let reference = file.block_texts();
        assert!(reference.len() > 3, "{name}: {reference:?}");
        for (how, input, packet) in [
            ("document packets", document_packets(&text, 200), 992),
            ("one line per packet", line_per_packet(&text), 992),
            ("few large packets", text.clone(), 992),
        ] {
            let s = rig.run("streaming.nc", Some(feeder(&input, packet, 1)), 5_000_000);
            assert_eq!(
                s.finish,
                Some(Finish::Ended),
                "{name} {how}: {:?}",
                s.of("error")
            );
            assert_eq!(s.block_texts(), reference, "{name} streamed as {how}");
        }
    }
}

#[test]
fn switch_takes_case_10_across_packets() {
    let rig = rig();
    let r = rig.run(
        "streaming.nc",
        Some(feeder(
            &document_packets(&repo_nc("switchstream.nc"), 200),
            992,
            1,
        )),
        5_000_000,
    );
    let texts = r.block_texts();
    assert!(texts.contains(&"N150 X100".to_string()), "{texts:?}");
    assert!(!texts
        .iter()
        .any(|t| t.starts_with("N060") || t.starts_with("N090") || t.starts_with("N120")));
}

#[test]
fn forward_goto_skips_into_later_packets() {
    let rig = rig();
    let r = rig.run(
        "streaming.nc",
        Some(feeder(
            &document_packets(&repo_nc("goto_forward.nc"), 200),
            992,
            1,
        )),
        5_000_000,
    );
    let texts = r.block_texts();
    assert_eq!(
        texts,
        [
            "N01 G01 X0 Y0 Z0 F1000",
            "N10 G01 X20",
            "N40: G01 X40",
            "N80: G01 X-20",
            "N90 G01 X-40",
            "M30"
        ]
    );
}

fn stream_errors(rig: &Rig, text: &str) -> Vec<u64> {
    let r = rig.run("streaming.nc", Some(feeder(text, 992, 1)), 100_000);
    assert_eq!(r.finish, Some(Finish::Error), "{text:?}: {}", r.log);
    r.error_codes()
}

fn file_errors(rig: &Rig, text: &str) -> Vec<u64> {
    rig.program("t.nc", text);
    let r = rig.run("t.nc", None, 100_000);
    assert_eq!(r.finish, Some(Finish::Error), "{text:?}: {}", r.log);
    r.error_codes()
}

/// `#FLUSH` is refused under each cross-block function with the kernel's id for it (TF5200
/// diagnosis IDs 20651, 120102, 120434).
#[test]
fn flush_refusals_name_the_function() {
    let rig = rig();
    for (text, code) in [
        ("G41 D1\nX1 F100\n#FLUSH\nM30\n", 20651),
        ("G151\n#FLUSH\nM30\n", 120102),
        ("#HSC ON [OPMODE 2]\n#FLUSH\nM30\n", 120434),
    ] {
        assert_eq!(stream_errors(&rig, text), [code], "{text:?}");
    }
}

#[test]
fn streaming_rules_have_their_error_numbers() {
    let rig = rig();
    for (text, code) in [
        ("N10 X1 F100\n$FOR P1=1,3,1\nX2\n$ENDFOR\nM30\n", 21478),
        ("P1=1\n$WHILE P1 < 3\nP1=P1+1\n$ENDWHILE\nM30\n", 21478),
        ("$DO\nX1 F100\n$ENDDO P1 > 0\nM30\n", 21478),
        ("$REPEAT\nX1 F100\n$UNTIL 1\nM30\n", 21478),
        ("N10: X1 F100\nN20 $GOTO N10\nM30\n", 21477),
        ("LL sub\nM30\n", 21479),
        ("N10 $GOTO N99\nN20 X1 F100\nM30\n", 20840),
        ("N10: X1 F100\nN10: X2\nM30\n", 20836),
        ("N10 #FLUSH CONTINUE\nG41 D1\nX1 F100\n#FLUSH\nM30\n", 20651),
    ] {
        assert_eq!(stream_errors(&rig, text), [code], "{text:?}");
    }
}

#[test]
fn file_programs_may_loop_and_jump_back() {
    let rig = rig();
    rig.program(
        "loops.nc",
        "P1=0\n$FOR P2=1,3,1\nP1=P1+1\n$ENDFOR\n$WHILE P1 < 5\nP1=P1+1\n$ENDWHILE\n$DO\nP1=P1+1\n$ENDDO P1 < 7\n\
         $REPEAT\nP1=P1+1\n$UNTIL P1 >= 9\nN50: P1=P1+1\n$IF P1 < 11 $GOTO N50\n$IF P1 == 11\nX[P1] F1000\n$ENDIF\nM30\n",
    );
    let r = rig.run("loops.nc", None, 1_000_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{:?}", r.of("error"));
    assert!((r.machine.channels()[0].report().position[0] - 11.0).abs() < 1e-9);
    // The block counter counts every decoded line, each loop pass included.
    let last = r.of("block").last().unwrap()["counter"].as_u64().unwrap();
    assert!(last > 20, "{last}");
}

#[test]
fn structure_errors_in_files() {
    let rig = rig();
    for (text, code) in [
        ("$ENDIF\nM30\n", 20218),
        ("$ELSE\nM30\n", 20214),
        ("$CASE 1\nM30\n", 20221),
        ("$ENDFOR\nM30\n", 20232),
        ("$IF 0\nX1 F100\nM30\n", 21501),
        ("M17\n", 20376),
        ("$GOTO [NOWHERE]\nM30\n", 20840),
        ("[A] X1 F100\n[A] X2\n$GOTO [A]\nM30\n", 20836),
        ("LL missing\nM30\n", 20373),
        ("G999 X1\nM30\n", 20131),
        ("M70000\nM30\n", 20157),
        ("#NOTHING\nM30\n", 20209),
    ] {
        assert_eq!(file_errors(&rig, text), [code], "{text:?}");
    }
}

#[test]
fn subroutines_cycles_locals_and_variables() {
    let rig = rig();
    rig.program("sub1.nc", "V.L.DEPTH = 1\nP10 = P10 + 1\nL sub2.nc\nM17\n");
    rig.program("sub2.nc", "P10 = P10 + V.L.DEPTH\nM29\n");
    rig.program("cyc.cyc", "X[@P1] Y[@P2] F1000\nM17\n");
    rig.program(
        "main.nc",
        "%L LOC\nP11 = 7\nM17\n%main\nP10 = 0\nV.S.KEEP = 3\nL sub1.nc\nLL LOC\nL CYCLE [NAME=cyc.cyc @P1=P10 @P2=P11]\nM30\n",
    );
    let r = rig.run("main.nc", None, 1_000_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{:?}", r.of("error"));
    let p = r.machine.channels()[0].report().position;
    assert_eq!((p[0], p[1]), (2.0, 7.0));
}

/// A control block whose branch ran, still open at M30 or M17, is the warning 20375 and the
/// program goes on (TF5200 diagnosis ID 20375, class 1); a false branch still waiting for its
/// end when the file ends is 21501 in the main program, 21502 in a global subroutine, 21500
/// in a local one (TF5200 diagnosis IDs 21500–21502).
#[test]
fn open_control_blocks_at_the_end_valid_warn_invalid_stop() {
    let rig = rig();
    rig.program("open.nc", "X1 F100\n$IF 1\nM17\n");
    rig.program("m.nc", "L open.nc\n$IF 1\nX9\nM30\n");
    let r = rig.run("m.nc", None, 100_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{:?}", r.of("error"));
    let warnings: Vec<_> = r.of("warning").iter().map(|w| w["code"].clone()).collect();
    assert_eq!(warnings, [20375, 20375]);
    assert!(r.block_texts().contains(&"X9".to_string()));
    rig.program("invalid.nc", "$IF 0\nX1 F100\nM17\n");
    for (text, code) in [
        ("$IF 0\nX1 F100\nM30\n", 21501),
        ("$SWITCH 2\n$CASE 1\nX1 F100\nM30\n", 21501),
        ("L invalid.nc\nM30\n", 21502),
        ("%L S\n$IF 0\nX1 F100\nM17\n%main\nLL S\nM30\n", 21500),
    ] {
        assert_eq!(file_errors(&rig, text), [code], "{text:?}");
    }
}

#[test]
fn m30_in_a_subroutine_warns_and_ends() {
    let rig = rig();
    rig.program("s.nc", "X1 F100\nM30\n");
    rig.program("m.nc", "L s.nc\nX9\nM30\n");
    let r = rig.run("m.nc", None, 100_000);
    assert_eq!(r.finish, Some(Finish::Ended));
    assert_eq!(r.of("warning")[0]["code"], 20377);
    assert!(!r.block_texts().contains(&"X9".to_string()));
}

#[test]
fn block_skip_follows_the_mask() {
    let rig = rig();
    rig.program("skip.nc", "X1 F100\n/ X2\n/3 X3\nM30\n");
    let r = rig.run("skip.nc", None, 100_000);
    assert_eq!(r.block_texts(), ["X1 F100", "/ X2", "/3 X3", "M30"]);
    let r = rig.run_with("skip.nc", None, 100_000, |m| {
        m.apply(&common::tick0(Duration::ZERO), 1, Op::SkipMask(1 << 3));
    });
    assert_eq!(r.block_texts(), ["X1 F100", "/ X2", "M30"]);
}

#[test]
fn comment_block_spans_packets() {
    let rig = rig();
    let text = "N1 X1 F100\n#COMMENT BEGIN\nN2 X2\n\x0c 100\nN3 X3\n#COMMENT END\nN4 X4\nM30\n";
    let r = rig.run("streaming.nc", Some(feeder(text, 992, 1)), 100_000);
    assert_eq!(r.block_texts(), ["N1 X1 F100", "N4 X4", "M30"]);
}

/// A program with modal state worth restoring: feed, spindle, coolant, tool, G91, plane.
const SEARCH_PROGRAM: &str = "N10 G0 X0 Y0 Z0\nN20 T3 S1200 M3\nN30 G1 X10 F500\nN40 M8\nN50 G18\nN60 G91 Y5\nN70 G90 X20 F700\nN80 G17 Y30\nN90 X40\nM30\n";

/// The program cut at N70, which only ends it: the state after a search to N70 is then the
/// state the search collected, and the full run's final state is the state at that point.
fn cut_at_n70() -> String {
    let head: String = SEARCH_PROGRAM
        .lines()
        .take_while(|l| !l.starts_with("N70"))
        .map(|l| format!("{l}\n"))
        .collect();
    head + "N70 M30\n"
}

/// Byte offset of N70 as the channel counts it (CR LF in a stream).
fn offset_of_n70(stream: bool) -> u64 {
    let at = SEARCH_PROGRAM.find("N70").unwrap();
    let lines_before = SEARCH_PROGRAM[..at].matches('\n').count();
    (at + if stream { lines_before } else { 0 }) as u64
}

fn run_search(
    rig: &Rig,
    text: &str,
    stream: bool,
    target: Option<SearchTarget>,
) -> common::RunResult {
    let set = |m: &mut ncchannel::machine::Machine| {
        m.apply(&common::tick0(Duration::ZERO), 1, Op::SearchAt(target));
    };
    let r = if stream {
        rig.run_with("streaming.nc", Some(feeder(text, 992, 1)), 1_000_000, set)
    } else {
        rig.program("search.nc", text);
        rig.run_with("search.nc", None, 1_000_000, set)
    };
    assert_eq!(r.finish, Some(Finish::Ended), "{:?}", r.of("error"));
    r
}

#[test]
fn block_search_by_number_counter_and_offset_restores_the_state_of_a_full_run() {
    let rig = rig();
    let cut = cut_at_n70();
    for stream in [false, true] {
        let full = run_search(&rig, &cut, stream, None);
        let full_modal = full.machine.channels()[0].report().modal;
        assert_eq!(
            (
                full_modal.tool,
                full_modal.spindle_rpm,
                full_modal.coolant_flood
            ),
            (3, 1200.0, true)
        );
        for target in [
            SearchTarget::BlockNumber(70),
            SearchTarget::Counter(7),
            SearchTarget::Offset(offset_of_n70(stream)),
        ] {
            // Snapshot: the state collected by the search equals the full run's at N70 …
            let s = run_search(&rig, &cut, stream, Some(target));
            assert_eq!(
                &s.machine.channels()[0].report().modal,
                &full_modal,
                "{target} stream={stream}"
            );
            // … the positioning move brought the axes where the full run had them …
            assert_eq!(
                s.machine.channels()[0].report().position,
                full.machine.channels()[0].report().position,
                "{target}"
            );
            let ev = s.of("search");
            assert_eq!(ev.len(), 1, "{target}");
            assert_eq!(ev[0]["found"], true);
            assert_eq!(ev[0]["target"], target.to_string());
            // … and execution continues at the target, the blocks before it not executed.
            let r = run_search(&rig, SEARCH_PROGRAM, stream, Some(target));
            assert_eq!(
                r.block_texts(),
                ["N70 G90 X20 F700", "N80 G17 Y30", "N90 X40", "M30"],
                "{target} stream={stream}"
            );
        }
    }
}

#[test]
fn block_search_target_not_found_is_20704() {
    let rig = rig();
    rig.program("search.nc", SEARCH_PROGRAM);
    let r = rig.run_with("search.nc", None, 1_000_000, |m| {
        let target = Some(SearchTarget::BlockNumber(999));
        m.apply(&common::tick0(Duration::ZERO), 1, Op::SearchAt(target));
    });
    assert_eq!(r.error_codes(), [20704]);
}
