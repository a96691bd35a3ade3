//! cargo-fuzz target: see `checks::machine_requests` in fuzz/src/checks.rs for what it asserts.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| ncchannel_fuzz::checks::machine_requests(data));
