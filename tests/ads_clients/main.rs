//! Real ADS clients from outside (pyads, Node's ads-client): ignored by default, run with `cargo
//! test --test ads_clients -- --ignored` once the clients are installed (`.ci/run` shows how).

#[path = "../support/mod.rs"]
mod support;

mod ads_local_idioms;
mod ads_node;
mod ads_node_stall;
mod ads_pyads;
mod ads_techno_clients;
#[path = "../ads/techno_rig.rs"]
mod techno_rig;
