//! cargo-fuzz target: see `checks::expr_eval` in fuzz/src/checks.rs for what it asserts.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| ncchannel_fuzz::checks::expr_eval(data));
