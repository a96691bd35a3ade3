//! The fuzz targets' assertions (fuzz/src/checks.rs) over inputs kept in the repository: every
//! file under `fuzz/regressions/<target>/` (inputs a fuzzer once found, kept after the fix),
//! and the repository's own NC programs and parameter lists (the seed corpus). Runs in plain
//! `cargo test`, without libFuzzer or a nightly toolchain.

#[path = "../fuzz/src/checks.rs"]
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
    ("dnc_split", checks::dnc_split),
    ("stream_buffer", checks::stream_buffer),
    ("channel_program", checks::channel_program),
    ("param_folder", checks::param_folder),
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
