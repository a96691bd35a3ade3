//! Program files larger than a tick's inline read budget are read by the loader thread: no
//! tick reads more than the budget (the store's own counter says so), and the program runs
//! exactly as when it was read in one piece.

use crate::support::Rig;
use ncchannel::INLINE_READ_BYTES_PER_TICK;

/// `lines` parameter blocks, then `tail`: a program about 8 bytes a line.
fn big_program(lines: usize, tail: &str) -> String {
    let mut p = String::new();
    for i in 0..lines {
        p.push_str(&format!("P1={i}\n"));
    }
    p.push_str(tail);
    p
}

/// Three times the inline budget: before, the whole file was read inside one tick.
fn lines_for_three_budgets() -> usize {
    3 * INLINE_READ_BYTES_PER_TICK as usize / 8
}

#[test]
fn a_large_subprogram_is_read_off_the_tick_and_runs_whole() {
    let rig = Rig::new();
    let lines = lines_for_three_budgets();
    let sub = big_program(lines, "X7\nM17\n");
    assert!(sub.len() as u64 > 2 * INLINE_READ_BYTES_PER_TICK);
    rig.program("big.nc", &sub);
    let main = "N1 G01 X1 F6000\nL big.nc\nN2 Y2\nM30\n";
    rig.program("main.nc", main);
    let r = rig.run("main.nc", None, 1_000_000);
    assert!(r.error_codes().is_empty(), "{:?}", r.error_codes());
    let texts = r.block_texts();
    assert_eq!(texts[..2], ["N1 G01 X1 F6000", "L big.nc"]);
    assert_eq!(texts[texts.len() - 4..], ["X7", "M17", "N2 Y2", "M30"]);
    let params: Vec<&String> = texts.iter().filter(|t| t.starts_with("P1=")).collect();
    assert_eq!(params.len(), lines, "every line of the subprogram ran once");
    assert_eq!(
        params.last().map(|t| t.as_str()),
        Some(&*format!("P1={}", lines - 1))
    );
    assert_eq!((r.position('X'), r.position('Y')), (7.0, 2.0));
    let files = r.machine.channels()[0].report().store;
    assert_eq!(files.opens, 2);
    assert_eq!(files.bytes_read, (main.len() + sub.len()) as u64);
    assert_eq!(files.loaded_off_tick, 1, "{files:?}");
    assert!(
        files.max_tick_read_bytes <= INLINE_READ_BYTES_PER_TICK,
        "{files:?}"
    );
}

#[test]
fn a_large_main_program_is_read_off_the_tick() {
    let rig = Rig::new();
    let lines = lines_for_three_budgets();
    rig.program("big_main.nc", &big_program(lines, "G01 X3 F6000\nM30\n"));
    let r = rig.run("big_main.nc", None, 1_000_000);
    assert!(r.error_codes().is_empty(), "{:?}", r.error_codes());
    assert_eq!(r.position('X'), 3.0);
    assert_eq!(r.of("program_start").len(), 1);
    let files = r.machine.channels()[0].report().store;
    assert_eq!((files.opens, files.loaded_off_tick), (1, 1), "{files:?}");
    assert!(files.max_tick_read_bytes <= INLINE_READ_BYTES_PER_TICK);
    // Virtual time waited for the loader with the clock stopped: that wait is counted apart,
    // not as the work of the tick that waited.
    assert!(
        r.stats.clock_stopped > std::time::Duration::ZERO,
        "{:?}",
        r.stats
    );
}

#[test]
fn a_program_read_in_the_tick_stops_no_clock() {
    let rig = Rig::new();
    rig.program(
        "small.nc",
        "G01 X3 F6000
M30
",
    );
    let r = rig.run("small.nc", None, 100_000);
    assert_eq!(r.position('X'), 3.0);
    assert_eq!(r.machine.channels()[0].report().store.loaded_off_tick, 0);
    assert_eq!(r.stats.clock_stopped, std::time::Duration::ZERO);
}

#[test]
fn a_file_without_line_ends_is_refused_at_its_first_line() {
    let rig = Rig::new();
    rig.program("one_line.nc", &"X".repeat(ncchannel::MAX_LINE_BYTES + 10));
    let r = rig.run("one_line.nc", None, 100_000);
    assert_eq!(r.error_codes(), [20200]);
    let e = &r.of("error")[0];
    assert_eq!(e["line"], 1, "{e}");
}

#[test]
fn long_lines_are_decoded_a_bounded_number_of_bytes_per_tick() {
    let rig = Rig::new();
    // 200 comment lines of 10,000 bytes: before, 64 of them (640 KB) were decoded per tick.
    let long = "x".repeat(10_000);
    let mut p = String::from("N1 G01 X1 F6000\n#COMMENT BEGIN\n");
    for _ in 0..200 {
        p.push_str(&long);
        p.push('\n');
    }
    p.push_str("#COMMENT END\nX2\nM30\n");
    rig.program("long_lines.nc", &p);
    let r = rig.run("long_lines.nc", None, 100_000);
    assert!(r.error_codes().is_empty(), "{:?}", r.error_codes());
    assert_eq!(r.block_texts(), ["N1 G01 X1 F6000", "X2", "M30"]);
    let stats = r.machine.channels()[0].report().decoder;
    assert!(
        stats.max_line_bytes_per_tick
            <= ncchannel::LINE_BYTES_PER_TICK + ncchannel::MAX_LINE_BYTES + 2,
        "{stats:?}"
    );
    assert!(stats.max_line_bytes_per_tick >= 10_000, "{stats:?}");
}
