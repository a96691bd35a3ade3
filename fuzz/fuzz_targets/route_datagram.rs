//! cargo-fuzz target: see `checks::route_datagram` in fuzz/src/checks.rs for what it asserts.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| ncchannel_fuzz::checks::route_datagram(data));
