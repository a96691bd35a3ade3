//! cargo-fuzz target: see `checks::program_check` in fuzz/src/checks.rs for what it asserts.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| ncchannel_fuzz::checks::program_check(data));
