//! The ISG dialect a CAM post-processor writes: every G function, M/H range and `#` command of
//! ISG's reference lists (tests/data/isg_reference.txt) is implemented, inert or refused as
//! docs/nc-language.md says; dwell forms, units, feed modes, G92, double programming, `#MSG`,
//! H functions; a 10,000-line post-processor program streamed and from a file; and
//! `ncchannel check` finding exactly what `run` finds.

use crate::support as common;

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command as Process;

use common::{feeder, Rig};
use ncchannel::channel::Finish;
use ncchannel::lang::codes;
use ncchannel::lang::dialect::{command_support, g_support, Support};
use ncchannel::lang::{check_program, parse_block, Body, Command};

fn reference() -> Vec<String> {
    let text = include_str!("../data/isg_reference.txt");
    text.lines()
        .filter(|l| !l.starts_with("# "))
        .map(str::to_string)
        .collect()
}

/// `G54 - G59` → 54..=59, `G02 Z.. K..` → 2, `G800 - G819` → 800..=819.
fn g_numbers(label: &str) -> Vec<u32> {
    let nums: Vec<u32> = label
        .split(|c: char| !c.is_ascii_digit())
        .filter(|s| !s.is_empty())
        .filter_map(|s| s.parse().ok())
        .collect();
    if label.contains(" - ") && nums.len() == 2 {
        (nums[0]..=nums[1]).collect()
    } else {
        nums.into_iter().take(1).collect()
    }
}

/// `#CS ADD/SELECT` → `CS`; `#ENABLE AX LINK|||#DISABLE AX LINK` → `ENABLE`, `DISABLE`.
fn command_keywords(label: &str) -> Vec<String> {
    label
        .split("|||")
        .flat_map(|p| p.split("..."))
        .filter_map(|p| p.strip_prefix('#'))
        .map(|p| {
            p.chars()
                .take_while(char::is_ascii_alphabetic)
                .collect::<String>()
        })
        .filter(|k| !k.is_empty())
        .collect()
}

/// The tables of docs/nc-language.md: first cell → last cell (`implemented`, `inert`,
/// `refused`), for rows whose first cell starts with `G` or `#`.
fn documented() -> BTreeMap<String, String> {
    let doc = std::fs::read_to_string(format!(
        "{}/docs/nc-language.md",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let mut out = BTreeMap::new();
    for line in doc.lines() {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        if cells.len() < 4 {
            continue;
        }
        let first = cells[1].trim_matches('`');
        let last = cells[cells.len() - 2];
        if (first.starts_with('G') || first.starts_with('#'))
            && matches!(last, "implemented" | "inert" | "refused")
        {
            out.insert(first.to_string(), last.to_string());
        }
    }
    out
}

fn word(s: Support) -> &'static str {
    match s {
        Support::Implemented => "implemented",
        Support::Inert => "inert",
        Support::Refused => "refused",
    }
}

/// The documented row for `G<g>`: `G54–G59` covers 54..=59.
fn doc_for_g(doc: &BTreeMap<String, String>, g: u32) -> Option<String> {
    doc.iter().find_map(|(k, v)| {
        let k = k.strip_prefix('G')?;
        let (lo, hi) = match k.split_once("–G") {
            Some((a, b)) => (a.parse::<u32>().ok()?, b.parse::<u32>().ok()?),
            None => {
                let n = k.parse::<u32>().ok()?;
                (n, n)
            }
        };
        (lo..=hi).contains(&g).then(|| v.clone())
    })
}

#[test]
fn every_reference_g_function_is_implemented_inert_or_refused_as_documented() {
    let doc = documented();
    let mut accepted = Vec::new();
    let mut seen = 0;
    for label in reference().iter().filter(|l| l.starts_with('G')) {
        for g in g_numbers(label) {
            seen += 1;
            let (support, _) = g_support(g).unwrap_or_else(|| panic!("{label}: G{g} unlisted"));
            assert_eq!(
                doc_for_g(&doc, g).as_deref(),
                Some(word(support)),
                "docs/nc-language.md on G{g}"
            );
            let parsed = parse_block(&format!("G{g}"));
            match support {
                Support::Refused => {
                    let e = parsed.expect_err(&format!("G{g} refused"));
                    assert_eq!((e.code, e.col), (codes::UNSUPPORTED, 1), "G{g}");
                    assert!(e.message.contains(&format!("G{g} ")), "{}", e.message);
                }
                _ => {
                    parsed.unwrap_or_else(|e| panic!("G{g}: {e}"));
                    accepted.push(g);
                }
            }
        }
    }
    assert!(seen > 150, "{seen} G numbers read from the reference");
    // Every accepted G runs in a channel (alone in its block; G04 with its time). G800–G819
    // call the subroutines a channel list configures: tests/lang/real_programs.rs runs them.
    accepted.retain(|g| !ncchannel::lang::gcall::G_CALLS.contains(g));
    let rig = Rig::new();
    let mut prog: String = accepted
        .iter()
        .map(|g| match g {
            4 => "G04 0.01\n".to_string(),
            _ => format!("G{g}\n"),
        })
        .collect();
    prog.push_str("G71 G90 G94 G40 G17 G53\nM30\n");
    rig.program("all_g.nc", &prog);
    let r = rig.run("all_g.nc", None, 1_000_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    assert_eq!(r.block_texts().len(), accepted.len() + 2);
    // A number in no list stays unknown.
    assert_eq!(parse_block("G7").unwrap_err().code, codes::UNKNOWN_G);
    assert_eq!(parse_block("G999").unwrap_err().code, codes::UNKNOWN_G);
}

#[test]
fn every_reference_command_is_implemented_inert_or_refused_as_documented() {
    let doc = documented();
    let mut inert = Vec::new();
    let mut seen = 0;
    for label in reference().iter().filter(|l| l.starts_with('#')) {
        for kw in command_keywords(label) {
            seen += 1;
            let support =
                command_support(kw.as_bytes()).unwrap_or_else(|| panic!("{label}: #{kw} unlisted"));
            assert_eq!(
                doc.get(&format!("#{kw}")).map(String::as_str),
                Some(word(support)),
                "docs/nc-language.md on #{kw}"
            );
            let parsed = parse_block(&format!("#{kw} ON [X1]"));
            match support {
                Support::Refused => {
                    let e = parsed.expect_err(&kw);
                    assert_eq!((e.code, e.col), (codes::UNSUPPORTED, 1), "#{kw}");
                    assert!(e.message.contains(&format!("#{kw} ")), "{}", e.message);
                }
                Support::Inert => {
                    let b = parsed.unwrap_or_else(|e| panic!("#{kw}: {e}"));
                    assert!(
                        matches!(&b.body, Body::Command(c) if matches!(**c, Command::Inert { .. })),
                        "#{kw}"
                    );
                    inert.push(kw);
                }
                // Implemented commands have their own syntax and tests.
                Support::Implemented => {}
            }
        }
    }
    assert!(seen > 180, "{seen} # commands read from the reference");
    let rig = Rig::new();
    let mut prog: String = inert.iter().map(|k| format!("#{k} [A=1]\n")).collect();
    prog.push_str("M30\n");
    rig.program("all_cmd.nc", &prog);
    let r = rig.run("all_cmd.nc", None, 1_000_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    assert_eq!(r.block_texts().len(), inert.len() + 1);
    assert_eq!(
        parse_block("#FOO").unwrap_err().code,
        codes::UNKNOWN_COMMAND
    );
}

#[test]
fn m_and_h_run_from_0_to_65535_and_h_functions_are_events() {
    for l in ["M0", "M100", "M65535", "H0", "H65535", "M3 M8 H12 H13"] {
        parse_block(l).unwrap_or_else(|e| panic!("{l}: {e}"));
    }
    for l in ["M65536", "M[1]"] {
        assert_eq!(parse_block(l).unwrap_err().code, codes::UNKNOWN_M, "{l}");
    }
    // An H number no channel list can define is the kernel's undefined H.
    for l in ["H65536", "H1.5", "H[1]"] {
        assert_eq!(parse_block(l).unwrap_err().code, codes::UNKNOWN_H, "{l}");
    }
    let rig = Rig::new();
    std::fs::write(
        rig.startup().with_file_name("channel1.lis"),
        "m_synch[100] MOS\nm_synch[65535] MOS\nh_synch[7] MOS\nh_synch[65535] MOS\n",
    )
    .unwrap();
    rig.program("h.nc", "M100 H7\nH65535 M65535\nM30\n");
    let r = rig.run("h.nc", None, 100_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    let hs: Vec<u64> = r
        .of("techno_output")
        .iter()
        .filter(|e| e["kind"] == "h")
        .map(|e| e["number"].as_u64().unwrap())
        .collect();
    assert_eq!(hs, [7, 65535]);
}

/// Double programming the decoder finds (TF5200 diagnosis): G41 and G42 in one block is
/// 20114, the same technology M function twice 20765 (`M10 M10`; M30 twice is a program
/// end, not a technology function); an undefined M above the self-defined M0–M999 is 20160,
/// one within them 20157.
#[test]
fn trc_twice_m_twice_and_unknown_internal_m_have_the_kernels_ids() {
    let rig = Rig::new();
    std::fs::write(
        rig.startup().with_file_name("channel1.lis"),
        "m_synch[10] MOS\nm_synch[5000] MOS\n",
    )
    .unwrap();
    for (block, code) in [
        ("G41 X10 Y20 G42", codes::TRC_TWICE),
        ("G42 G41 X10", codes::TRC_TWICE),
        ("G0 X10 M10 M10", codes::M_TWICE),
        ("M1001", codes::UNKNOWN_INTERNAL_M),
        ("M999", codes::UNKNOWN_M),
    ] {
        rig.program("twice.nc", &format!("G0 X0 Y0\n{block}\nM30\n"));
        let r = rig.run("twice.nc", None, 100_000);
        assert_eq!(r.error_codes(), [u64::from(code)], "{block}: {}", r.log);
    }
    // Defined in the channel's list, an M above M999 runs (docs/design-choices.md).
    rig.program("ok.nc", "G0 X0 Y0\nM10 M5000\nG41 G40 X1\nM30\n");
    let r = rig.run("ok.nc", None, 100_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
}

/// The combined assignments `+=`, `-=`, `*=`, `/=` (TF5200 diagnosis ID 20574 names "the
/// combined assignment operator /="): the target's value with the operand, printed back as
/// written; `/=` by 0 is 20574, a `/` by 0 inside an expression stays 20396.
#[test]
fn combined_assignments_compute_on_the_old_value_and_divide_by_zero_is_20574() {
    for line in ["P2/=P1", "P2+=[P1*2]", "V.L.X-=1", "P[3]*=2"] {
        let text = parse_block(line).unwrap().to_string();
        let (op, _) = line.split_at(line.find('=').unwrap() + 1);
        assert!(text.starts_with(op), "{line}: {text}");
        assert_eq!(parse_block(&text).unwrap().to_string(), text, "{line}");
    }
    let rig = Rig::new();
    rig.program(
        "comb.nc",
        "P1=4\nP2=10\nP2+=P1 P2*=3 P2-=2\nP2/=P1\nX[P2] F100\nM30\n",
    );
    let r = rig.run("comb.nc", None, 1_000_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    assert!((r.position('X') - 10.0).abs() < 1e-9, "{}", r.position('X'));
    for (prog, code) in [
        (
            "P1=0\nP2=1\nP2/=P1\nM30\n",
            codes::COMBINED_DIVISION_BY_ZERO,
        ),
        (
            "P1=0\nP2=1\nP2/=[1/P1]\nM30\n",
            codes::EVAL_DIVISION_BY_ZERO,
        ),
    ] {
        rig.program("div.nc", prog);
        let r = rig.run("div.nc", None, 100_000);
        assert_eq!(r.error_codes(), [u64::from(code)], "{prog}: {}", r.log);
    }
}

/// `P7=2.5`, a constant parameter and a literal, is stored where every other way of
/// naming the parameter reads and writes it (the decoder takes such a block on a shorter
/// path than an expression's).
#[test]
fn a_literal_assignment_is_read_back_by_every_way_of_naming_the_parameter() {
    let rig = Rig::new();
    rig.program(
        "lit.nc",
        "P7=2.5
P8=-0.125
P9=P7+P[8]
P[10]=[P9*2]
P10+=1
X[P7] Y[P8] Z[P10] F100
M30
",
    );
    let r = rig.run("lit.nc", None, 1_000_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    assert!((r.position('X') - 2.5).abs() < 1e-12, "{}", r.position('X'));
    assert!(
        (r.position('Y') + 0.125).abs() < 1e-12,
        "{}",
        r.position('Y')
    );
    assert!(
        (r.position('Z') - 5.75).abs() < 1e-12,
        "{}",
        r.position('Z')
    );
}

/// Channel time from the start of the block `text` to the start of the next block.
fn block_duration(r: &common::RunResult, text: &str) -> f64 {
    let blocks = r.of("block");
    let i = blocks
        .iter()
        .position(|b| b["text"] == text)
        .unwrap_or_else(|| panic!("{text} not run: {}", r.log));
    blocks[i + 1]["t"].as_f64().unwrap() - blocks[i]["t"].as_f64().unwrap()
}

#[test]
fn each_dwell_form_dwells_its_time() {
    let rig = Rig::new();
    for form in [
        "G04 2.5",
        "G4 2.5",
        "G04=2.5",
        "G04 P2",
        "G04 V.L.TIME",
        "G04 X2.5",
        "G4 F2.5",
        "G04 X[P1/2]",
        "#TIME 2.5",
        "#TIME [P1/2]",
    ] {
        rig.program(
            "dwell.nc",
            &format!("#VAR\nV.L.TIME\n#ENDVAR\nP1=5\nP2=2.5\nV.L.TIME=2.5\nM5\n{form}\nM5\nM30\n"),
        );
        let r = rig.run("dwell.nc", None, 1_000_000);
        assert_eq!(r.finish, Some(Finish::Ended), "{form}: {}", r.log);
        let t = block_duration(&r, form);
        assert!((t - 2.5).abs() < 0.01, "{form}: dwelled {t} s");
        // The time word is no feed: the modal feed stays unset.
        let c = &r.machine.channels()[0];
        assert_eq!(c.status().modal.feed_mm_per_min, 0.0, "{form}");
    }
}

/// `G04 X2 Y3 Z4`: X's time, one warning 20685 for each further axis, which does not move
/// (TF5200 diagnosis ID 20685 "Dwell time programmed with additional axes.", class 1:
/// processing continues).
#[test]
fn g04_with_further_axes_dwells_x_time_and_warns_for_each() {
    let rig = Rig::new();
    rig.program("dwell.nc", "G0 Y1 Z1\nG04 X2 Y3 Z4\nG0 X1\nM30\n");
    let r = rig.run("dwell.nc", None, 1_000_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    let t = block_duration(&r, "G04 X2 Y3 Z4");
    assert!((t - 2.0).abs() < 0.01, "dwelled {t} s");
    let warnings: Vec<u64> = r
        .of("warning")
        .iter()
        .filter_map(|w| w["code"].as_u64())
        .collect();
    assert_eq!(warnings, [u64::from(codes::DWELL_EXTRA_AXES); 2]);
    assert_eq!((r.position('Y'), r.position('Z')), (1.0, 1.0));
}

/// `G04 S10` waits ten turns of the main spindle at its programmed speed (TF5200 programming
/// manual, "Dwell time (G04), (#TIME)": `M3 S200`, `G04 S10` waits 3 s) and leaves the speed
/// as it was; a spindle that does not turn never completes them: 20752.
#[test]
fn g04_s_dwells_spindle_revolutions() {
    let rig = Rig::new();
    for (speed, form, seconds) in [("M3 S200", "G04 S10", 3.0), ("M4 S600", "G04 S2.5", 0.25)] {
        rig.program("rev.nc", &format!("{speed}\n{form}\nM5\nM30\n"));
        let r = rig.run("rev.nc", None, 1_000_000);
        assert_eq!(r.finish, Some(Finish::Ended), "{form}: {}", r.log);
        let t = block_duration(&r, form);
        assert!((t - seconds).abs() < 0.01, "{form}: dwelled {t} s");
    }
    for prog in [
        "G04 S10\nM30\n",
        "S200\nG04 S10\nM30\n",
        "M3 S200\nM5\nG04 S10\nM30\n",
    ] {
        rig.program("rev.nc", prog);
        let r = rig.run("rev.nc", None, 1_000_000);
        assert_eq!(
            r.error_codes(),
            [u64::from(codes::DWELL_RANGE_G04)],
            "{prog}: {}",
            r.log
        );
    }
}

/// Every case: the line, the error number, the 1-based column.
const REFUSED_BLOCKS: &[(&str, u32, u32)] = &[
    ("N10 G1 X1 X2 F100", codes::AXIS_TWICE, 11),
    ("G1 X1 Y2 Z3 Y4 F100", codes::AXIS_TWICE, 13),
    ("S1000 M3 S1500", codes::S_TWICE, 10),
    ("G1 X1 F100 F200", codes::F_TWICE, 12),
    ("T1 D1 T2", codes::WORD_TWICE, 7),
    ("T1 D1 D2", codes::D_TWICE, 7),
    ("G2 X1 Y1 I1 I2 F100", codes::ARC_CENTER_TWICE, 13),
    ("G04 Y2", codes::DWELL_NOT_FIRST_AXIS, 5),
    ("G4 F1.5 X2", codes::DWELL_NOT_ALONE, 9),
    ("G04 2 X1", codes::DWELL_DIRECT_AND_AXIS, 7),
    ("G04 X1 Y2 M3", codes::DWELL_NOT_ALONE, 11),
    ("G04 X1 M3", codes::DWELL_NOT_ALONE, 8),
    ("G1 G04 X1", codes::DWELL_NOT_ALONE, 1),
    ("G33 Z-10 K1.5", codes::UNSUPPORTED, 1),
    ("G90 G96 S200", codes::UNSUPPORTED, 5),
    ("#CS ON [0,0,0,0,0,45]", codes::UNSUPPORTED, 1),
    ("M70000", codes::UNKNOWN_M, 1),
    ("G7", codes::UNKNOWN_G, 1),
    ("#FOO BAR", codes::UNKNOWN_COMMAND, 1),
];

#[test]
fn each_double_programming_and_refusal_is_its_error_at_its_column_in_check_and_run() {
    let rig = Rig::new();
    for &(line, code, col) in REFUSED_BLOCKS {
        let e = parse_block(line).expect_err(line);
        assert_eq!((e.code, e.col), (code, col), "{line}: {}", e.message);
        let prog = format!("G1 X0 F100\n{line}\nM30\n");
        let d = check_program(&prog);
        assert_eq!(
            d.iter()
                .map(|d| (d.line, d.col, d.code))
                .collect::<Vec<_>>(),
            [(2, col as usize, code)],
            "check {line}"
        );
        rig.program("bad.nc", &prog);
        let r = rig.run("bad.nc", None, 100_000);
        assert_eq!(r.finish, Some(Finish::Error), "{line}");
        let err = r.of("error")[0].clone();
        assert_eq!(err["code"].as_u64(), Some(u64::from(code)), "{line}");
        assert_eq!(err["line"].as_u64(), Some(2), "{line}");
        let msg = err["msg"].as_str().unwrap();
        assert!(msg.ends_with(&format!("(column {col})")), "{line}: {msg}");
    }
}

#[test]
fn inch_scales_positions_and_feeds_and_g71_returns_to_mm() {
    let rig = Rig::new();
    rig.program("inch.nc", "G70 G1 X1 F10\nG71 G1 Y2\nM30\n");
    let r = rig.run("inch.nc", None, 1_000_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    assert!((r.position('X') - 25.4).abs() < 1e-6);
    assert!((r.position('Y') - 2.0).abs() < 1e-6);
    // 25.4 mm at 254 mm/min: 6 s (plus ramps).
    let t = block_duration(&r, "G70 G1 X1 F10");
    assert!((6.0..6.5).contains(&t), "{t} s");
}

#[test]
fn feed_per_revolution_is_f_times_s_and_needs_s() {
    let rig = Rig::new();
    rig.program(
        "g95.nc",
        "S1000 M3\nG95 G1 X10 F0.1\nG94 G1 X20 F100\nM30\n",
    );
    let r = rig.run("g95.nc", None, 1_000_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    // 10 mm at 0.1 mm/rev × 1000 rpm = 100 mm/min: 6 s, as the G94 block after it.
    let t95 = block_duration(&r, "G95 G1 X10 F0.1");
    let t94 = block_duration(&r, "G94 G1 X20 F100");
    assert!((6.0..6.5).contains(&t95), "{t95} s");
    assert!((t95 - t94).abs() < 0.01, "{t95} vs {t94}");
    rig.program("g95s.nc", "G95 G1 X10 F0.1\nM30\n");
    let r = rig.run("g95s.nc", None, 1_000_000);
    assert_eq!(r.finish, Some(Finish::Error));
    assert_eq!(r.error_codes(), [u64::from(codes::NO_FEED)]);
    assert!(r.log.contains("needs a spindle speed"), "{}", r.log);
}

/// A G01 block without F that does not move is no motion block and runs (the TF5200 example
/// of ID 21500 starts its main program with `N010 X0 Y0 Z0`); the first one that moves is
/// 20008 (TF5200 diagnosis ID 20008 "Feed rate in motion block is 0.").
#[test]
fn g01_without_feed_is_20008_only_when_it_moves() {
    let rig = Rig::new();
    rig.program("still.nc", "G1 X0 Y0 Z0\nG91 X0\nG90 X5\nM30\n");
    let r = rig.run("still.nc", None, 100_000);
    assert_eq!(r.error_codes(), [u64::from(codes::NO_FEED)], "{}", r.log);
    assert_eq!(r.of("error")[0]["line"].as_u64(), Some(3));
    assert_eq!(r.position('X'), 0.0);
}

#[test]
fn g92_makes_the_current_position_the_programmed_one() {
    let rig = Rig::new();
    rig.program("g92.nc", "G0 X10 Y5\nG92 X0 Y0\nG0 X5\nG53 G0 Y1\nM30\n");
    let r = rig.run("g92.nc", None, 1_000_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    assert!((r.position('X') - 15.0).abs() < 1e-9);
    assert!((r.position('Y') - 1.0).abs() < 1e-9);
}

#[test]
fn msg_is_an_event_and_the_channel_keeps_the_latest() {
    let rig = Rig::new();
    rig.program(
        "msg.nc",
        "#MSG [\"tool 1 in\"]\n#MSG SAVE [\"second\"]\nM30\n",
    );
    let r = rig.run("msg.nc", None, 100_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    let m: Vec<(&str, bool)> = r
        .of("message")
        .iter()
        .map(|e| (e["text"].as_str().unwrap(), e["save"].as_bool().unwrap()))
        .collect();
    assert_eq!(m, [("tool 1 in", false), ("second", true)]);
    assert_eq!(
        r.machine.channels()[0].status().message.as_deref(),
        Some("second")
    );
}

/// `#MSG SYN` is output "synchronous with processing state in interpolator" (TF5200
/// programming manual, "Programming a message (#MSG)"): its event comes when the motion
/// reaches its block, with that block's event, after the 6 s move before it; a message
/// without a mode comes when its block is decoded, before the move has run.
#[test]
fn msg_syn_comes_when_execution_reaches_its_block() {
    let rig = Rig::new();
    for (mode, at_block) in [("SYN ", true), ("SYN_ACK HMI ", true), ("", false)] {
        let text = format!("#MSG {mode}[\"X at %.0f\", P1]");
        rig.program(
            "msg.nc",
            &format!("P1=60\nG01 X60 F600\n{text}\nG01 X0\nM30\n"),
        );
        let r = rig.run("msg.nc", None, 1_000_000);
        assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
        let msg = r.of("message");
        assert_eq!(msg.len(), 1, "{}", r.log);
        assert_eq!(msg[0]["text"], "X at 60");
        let t = msg[0]["t"].as_f64().unwrap();
        let block = r.of("block");
        let reached = block.iter().find(|b| b["text"] == text.as_str()).unwrap()["t"]
            .as_f64()
            .unwrap();
        if at_block {
            assert_eq!(t, reached, "{mode}: {}", r.log);
            assert!(t >= 6.0, "{mode}: {t}");
        } else {
            assert!(t < 1.0, "{mode}: {t}");
        }
        // The motion did not stop for it: X60 then X0 is one 12 s path in all.
        let end = r.of("program_end")[0]["t"].as_f64().unwrap();
        assert!(end < 12.5, "{mode}: ended at {end}");
    }
}

/// A program in the style of a TwinCAT CAM post: `%`, comments, the modal header, a tool
/// change, spindle, rapid and feed moves, arcs, `M30`. `lines` lines in all.
fn post_program(lines: usize) -> String {
    let mut out = vec![
        "%".to_string(),
        "(POST: TWINCAT CNC - ISG DIALECT)".to_string(),
        "(PART: POCKET 40X40)".to_string(),
        "N10 G71 G90 G94 G17 G40 G80".to_string(),
        "N20 G54".to_string(),
        "N30 T1 D1 M6 (END MILL D6)".to_string(),
        "N40 S12000 M3".to_string(),
        "N50 G0 X0 Y0 Z5".to_string(),
        "N60 #MSG [\"ROUGHING\"]".to_string(),
        "N70 G1 Z-1 F600".to_string(),
    ];
    let mut n = 80;
    let mut k = 0usize;
    // Current X/Y: arcs are half circles of radius 0.025 mm out and back.
    let (mut px, mut py) = (0.0f64, 0.0f64);
    while out.len() < lines - 3 {
        let line = match k % 10 {
            0 => format!("N{n} G2 X{:.3} Y{py:.3} I0.025 J0 F1200", px + 0.05),
            1 => format!("N{n} G3 X{px:.3} Y{py:.3} I-0.025 J0"),
            2 => format!("N{n} G0 Z1"),
            3 => format!("N{n} G1 Z-1 F600"),
            4 => format!("(PASS {k})"),
            5 => format!("N{n} G04 0.001"),
            _ => {
                px = (k % 40) as f64 * 0.05;
                py = (k % 23) as f64 * 0.05;
                format!("N{n} G1 X{px:.3} Y{py:.3} F1500")
            }
        };
        out.push(line);
        n += 10;
        k += 1;
    }
    out.push(format!("N{n} G0 Z5 M5"));
    out.push(format!("N{} G0 X0 Y0", n + 10));
    out.push(format!("N{} M30", n + 20));
    out.push(String::new());
    out.join("\n")
}

#[test]
fn a_10000_line_post_processor_program_runs_streamed_and_from_a_file_with_identical_blocks() {
    let text = post_program(10_000);
    assert_eq!(text.lines().count(), 10_000);
    let rig = Rig::new();
    rig.program("post.nc", &text);
    let file = rig.run("post.nc", None, 50_000_000);
    assert_eq!(
        file.finish,
        Some(Finish::Ended),
        "{}",
        file.error_codes().len()
    );
    let streamed = rig.run("streaming.nc", Some(feeder(&text, 992, 1)), 50_000_000);
    assert_eq!(
        streamed.finish,
        Some(Finish::Ended),
        "{:?}",
        streamed.error_codes()
    );
    let (a, b) = (file.block_texts(), streamed.block_texts());
    assert!(a.len() > 8_000, "{} blocks", a.len());
    assert_eq!(a, b);
    assert_eq!(file.of("message").len(), 1);
    // The same program passes the static check.
    assert_eq!(check_program(&text), []);
}

fn cli(args: &[&str]) -> (i32, String) {
    let out = Process::new(env!("CARGO_BIN_EXE_ncchannel"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let text =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    (out.status.code().unwrap_or(-1), text)
}

#[test]
fn run_takes_a_file_path_and_a_skip_mask_and_check_agrees() {
    let dir = tempfile::tempdir().unwrap();
    let prog = dir.path().join("cam.nc");
    std::fs::write(
        &prog,
        "N10 G71 G90 G94\nX1 F100\n/ X2\n/3 X3\nL sub.nc\nM30\n",
    )
    .unwrap();
    std::fs::write(dir.path().join("sub.nc"), "Y1\nM17\n").unwrap();
    let events = dir.path().join("ev.jsonl");
    let p = prog.to_str().unwrap();
    let e = events.to_str().unwrap();
    let (code, out) = cli(&["run", p, "--events", e]);
    assert_eq!(code, 0, "{out}");
    let texts = |path: &Path| -> Vec<String> {
        let ev: Vec<serde_json::Value> = std::fs::read_to_string(path)
            .unwrap()
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        common::block_texts(&ev)
    };
    assert!(texts(&events).contains(&"/3 X3".to_string()));
    let (code, out) = cli(&["run", p, "--skip-mask", "0x8", "--events", e]);
    assert_eq!(code, 0, "{out}");
    let t = texts(&events);
    assert!(!t.contains(&"/3 X3".to_string()) && t.contains(&"/ X2".to_string()));
    assert!(
        t.contains(&"Y1".to_string()),
        "subroutine next to the file: {t:?}"
    );
    // A relative path from the crate folder.
    let (code, out) = cli(&["run", "nc/demo.nc", "--max-ticks", "10"]);
    assert!(code == 0 || code == 3, "{out}");
    // check and run agree on a refused block.
    std::fs::write(&prog, "G1 X1 X2 F100\nM30\n").unwrap();
    let (code, out) = cli(&["check", p]);
    assert_eq!(code, 1, "{out}");
    assert!(out.contains(":1:7:") && out.contains("20203"), "{out}");
    let (code, out) = cli(&["run", p]);
    assert_eq!(code, 1, "{out}");
    // The summary names the program line that raised the error, as the event log does.
    assert!(
        out.contains("error 20203") && out.contains("(cam.nc, line 1)"),
        "{out}"
    );
}
