//! Soak runs: the soak scenarios and `serve --soak` (its pyads client tests are ignored by default:
//! `cargo test --test soak -- --ignored`).

mod campaign;
mod serve_soak;
mod soak;
