//! Hardening: what hostile or careless input does to a channel, and the fuzz targets' checks over
//! the kept inputs.

#[path = "../support/mod.rs"]
mod support;

mod fuzz_regressions;
mod hardening;
