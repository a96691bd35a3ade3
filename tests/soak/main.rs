//! Soak runs: the soak scenarios and `serve --soak` (its pyads client tests are ignored by default:
//! `cargo test --test soak -- --ignored`).

mod campaign;
mod plc;
mod serve_soak;
mod soak;
