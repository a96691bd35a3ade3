//! Jumps in programs with very many labels: the label index is built a slice per tick (the
//! decoder's own counters bound each tick's scan), bounded in size, and the jump still lands.

use crate::support::{Rig, RunResult};
use ncchannel::{LABEL_SCAN_BYTES_PER_TICK, LABEL_SCAN_LINES_PER_TICK, MAX_INDEXED_LABELS};

/// A program that jumps over `labels` string-labelled blocks to the last label, or calls the
/// `%L` section after them (`call`), and what it runs.
fn many_labels(labels: usize, call: bool) -> String {
    let mut p = String::from("%main\nN1 G01 X0 F6000\n");
    p.push_str(if call {
        "LL SUB\nN2 X99\nM30\n"
    } else {
        "$GOTO [LAST]\nN2 X99\n"
    });
    for i in 0..labels {
        p.push_str(&format!("[L{i}] P1={i}\n"));
    }
    p.push_str(if call {
        "%L SUB\nX3\nM17\n"
    } else {
        "[LAST] X5\nM30\n"
    });
    p
}

fn run_many(labels: usize, call: bool) -> RunResult {
    let rig = Rig::new();
    rig.program("many.nc", &many_labels(labels, call));
    rig.run("many.nc", None, 2_000_000)
}

/// No tick's label scan read more than the budget: the scan of a file of any size is spread
/// over ticks (before, the whole file was scanned in the tick of the `$GOTO`).
fn assert_scan_bounded(r: &RunResult, lines: usize) {
    let stats = r.machine.channels()[0].report().decoder;
    assert!(
        stats.max_scan_lines_per_tick <= LABEL_SCAN_LINES_PER_TICK,
        "{stats:?}"
    );
    assert!(
        stats.max_scan_bytes_per_tick <= LABEL_SCAN_BYTES_PER_TICK + ncchannel::MAX_LINE_BYTES,
        "{stats:?}"
    );
    // The file was scanned (each of its lines once per scan), in many ticks.
    assert!(
        lines > 10 * LABEL_SCAN_LINES_PER_TICK,
        "a file worth spreading"
    );
    assert!(stats.max_scan_lines_per_tick > 0, "{stats:?}");
}

#[test]
fn a_jump_over_many_labels_is_indexed_over_many_ticks_and_lands() {
    let labels = 20_000;
    let r = run_many(labels, false);
    assert!(r.error_codes().is_empty(), "{:?}", r.error_codes());
    assert_eq!(
        r.block_texts(),
        ["N1 G01 X0 F6000", "[LAST] X5", "M30"],
        "the jump lands on the last label"
    );
    assert_eq!(r.position('X'), 5.0);
    assert_scan_bounded(&r, labels);
    assert_eq!(r.machine.channels()[0].report().decoder.label_scans, 1);
}

#[test]
fn more_labels_than_the_index_holds_warn_once_and_are_searched_at_the_jump() {
    let labels = MAX_INDEXED_LABELS + 100;
    let r = run_many(labels, false);
    let warnings: Vec<u64> = r
        .of("warning")
        .iter()
        .map(|e| e["code"].as_u64().unwrap())
        .collect();
    assert_eq!(
        warnings,
        [20829],
        "the kernel's 'too many labels' warning, once"
    );
    assert!(r.error_codes().is_empty(), "{:?}", r.error_codes());
    assert_eq!(r.block_texts(), ["N1 G01 X0 F6000", "[LAST] X5", "M30"]);
    assert_scan_bounded(&r, labels);
    // The index, then a targeted search for the label that found no room.
    assert_eq!(r.machine.channels()[0].report().decoder.label_scans, 2);
}

#[test]
fn a_local_call_after_many_labels_finds_its_section() {
    let labels = 20_000;
    let r = run_many(labels, true);
    assert!(r.error_codes().is_empty(), "{:?}", r.error_codes());
    assert_eq!(
        r.block_texts(),
        ["N1 G01 X0 F6000", "LL SUB", "X3", "M17", "N2 X99", "M30"],
        "the section runs, then the program goes on after the call"
    );
    assert_scan_bounded(&r, labels);
}

#[test]
fn a_label_defined_twice_is_still_found_by_the_sliced_scan() {
    let rig = Rig::new();
    let mut p = many_labels(5_000, false);
    p.push_str("[L4999] X1\n");
    assert!(p.contains("[L4999] P1=4999"));
    rig.program("twice.nc", &p);
    let r = rig.run("twice.nc", None, 200_000);
    assert_eq!(r.error_codes(), [20836]);
}

#[test]
fn more_block_number_labels_than_the_index_holds_warn_with_our_id() {
    let labels = MAX_INDEXED_LABELS + 10;
    let mut p = String::from("N1 G01 X0 F6000\n$GOTO N9999999\nN2 X99\n");
    for i in 10..10 + labels {
        p.push_str(&format!("N{i}:\n"));
    }
    p.push_str("N9999999: X6\nM30\n");
    let rig = Rig::new();
    rig.program("numbers.nc", &p);
    let r = rig.run("numbers.nc", None, 2_000_000);
    let warnings: Vec<u64> = r
        .of("warning")
        .iter()
        .map(|e| e["code"].as_u64().unwrap())
        .collect();
    assert_eq!(warnings, [900113]);
    assert!(r.error_codes().is_empty(), "{:?}", r.error_codes());
    assert_eq!(r.position('X'), 6.0);
    assert_scan_bounded(&r, labels);
}
