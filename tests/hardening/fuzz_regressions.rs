//! The fuzz targets' assertions (fuzz/src/checks.rs) over inputs kept in the repository: every
//! file under `fuzz/regressions/<target>/` (inputs a fuzzer once found, kept after the fix),
//! and the repository's own NC programs and parameter lists (the seed corpus). Runs in plain
//! `cargo test`, without libFuzzer or a nightly toolchain.

#[path = "../../fuzz/src/checks.rs"]
#[allow(dead_code)]
mod checks;

use std::fs;
use std::path::{Path, PathBuf};

/// A target's name and its check.
type Target = (&'static str, fn(&[u8]));

const TARGETS: &[Target] = &[
    ("nc_line", checks::nc_line),
    ("nc_roundtrip", checks::nc_roundtrip),
    ("expr_eval", checks::expr_eval),
    ("program_check", checks::program_check),
    ("param_list", checks::param_list),
    ("ams_codec", checks::ams_codec),
    ("route_datagram", checks::route_datagram),
    ("dnc_split", checks::dnc_split),
    ("stream_buffer", checks::stream_buffer),
    ("channel_program", checks::channel_program),
    ("param_folder", checks::param_folder),
    ("machine_requests", checks::machine_requests),
];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn files_in(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    files
}

#[test]
fn every_kept_regression_input_passes_its_target() {
    let mut ran = 0;
    for (target, check) in TARGETS {
        for file in files_in(&root().join("fuzz/regressions").join(target)) {
            let data = fs::read(&file).unwrap();
            check(&data);
            ran += 1;
        }
    }
    assert!(ran > 0, "no regression inputs found under fuzz/regressions");
}

#[test]
fn shipped_programs_pass_the_nc_targets() {
    let programs = files_in(&root().join("nc"));
    assert!(programs.len() > 5);
    for file in programs {
        let data = fs::read(&file).unwrap();
        checks::program_check(&data);
        checks::dnc_split(&data);
        checks::channel_program(&data);
        for line in data.split(|&b| b == b'\n') {
            let line = line.strip_suffix(b"\r").unwrap_or(line);
            checks::nc_line(line);
            checks::nc_roundtrip(line);
        }
    }
}

#[test]
fn shipped_parameter_lists_pass_the_list_target() {
    let mut lists = files_in(&root().join("params"));
    lists.extend(files_in(&root().join("params/soak")));
    lists.retain(|p| p.extension().is_some_and(|e| e == "lis"));
    assert!(!lists.is_empty());
    for file in lists {
        checks::param_list(&fs::read(&file).unwrap());
    }
}

/// The machine target on a sequence a client really sends: stream lines written before and
/// after the start, a hold and resume, a request given up, a reset, a restart. The lines run
/// in order, each once (the target's assertions), and some run at all.
#[test]
fn machine_requests_run_streamed_lines_in_order_through_hold_reset_and_give_up() {
    use checks::ClientStep::*;
    let lines = |x| Lines {
        lines: 5,
        x,
        feed: 200,
        flush: true,
    };
    let steps = vec![
        lines(0),
        Start,
        lines(10),
        Ticks(50),
        Hold,
        Ticks(20),
        lines(20),
        Resume,
        Ticks(200),
        GiveUp,
        lines(30),
        Status,
        Override(50),
        Ticks(100),
        Raw(b"G01 X\n".to_vec()),
        Ticks(10),
        Reset,
        lines(40),
        Start,
        lines(50),
        Ticks(255),
        Ticks(255),
    ];
    let executed = checks::machine_steps(steps);
    assert!(executed >= 10, "only {executed} lines executed");
}

/// The machine target over a few hundred pseudo-random byte strings, so `cargo test` covers
/// it without libFuzzer (the numbers come from a fixed linear congruential generator).
#[test]
fn machine_requests_survive_pseudo_random_sequences() {
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 33) as u8
    };
    for _ in 0..200 {
        let len = usize::from(next()) * 4;
        let data: Vec<u8> = (0..len).map(|_| next()).collect();
        checks::machine_requests(&data);
    }
}
