//! cargo-fuzz target: see `checks::dnc_split` in fuzz/src/checks.rs for what it asserts.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| ncchannel_fuzz::checks::dnc_split(data));
