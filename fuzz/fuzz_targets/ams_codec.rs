//! cargo-fuzz target: see `checks::ams_codec` in fuzz/src/checks.rs for what it asserts.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| ncchannel_fuzz::checks::ams_codec(data));
