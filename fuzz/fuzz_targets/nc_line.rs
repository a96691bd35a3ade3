//! cargo-fuzz target: see `checks::nc_line` in fuzz/src/checks.rs for what it asserts.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| ncchannel_fuzz::checks::nc_line(data));
