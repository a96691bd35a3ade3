//! The fuzz targets' bodies. `checks.rs` is also compiled into the main crate's
//! `tests/hardening/fuzz_regressions.rs`, so every kept input runs in plain `cargo test`.
pub mod checks;
