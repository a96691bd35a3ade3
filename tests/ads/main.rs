//! The ADS server: frames on the wire, `serve`, streaming over ADS, the documented object map,
//! channel commands, housekeeping, the `ads` crate and TwinSharp as clients, and abuse.

#[path = "../support/mod.rs"]
mod support;

mod ads_abuse;
mod ads_channel_commands;
mod ads_crate_client;
mod ads_docs;
mod ads_ext_vars;
mod ads_housekeeping;
mod ads_model_objects;
mod ads_serve;
mod ads_server;
mod ads_state_control;
mod ads_stream;
mod ads_symbols;
mod ads_techno;
mod ads_twinsharp;
mod ads_unholdable;
mod techno_rig;
