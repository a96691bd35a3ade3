//! cargo-fuzz target: see `checks::param_folder` in fuzz/src/checks.rs for what it asserts.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| ncchannel_fuzz::checks::param_folder(data));
