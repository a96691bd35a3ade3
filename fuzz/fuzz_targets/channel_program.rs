//! cargo-fuzz target: see `checks::channel_program` in fuzz/src/checks.rs for what it asserts.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| ncchannel_fuzz::checks::channel_program(data));
