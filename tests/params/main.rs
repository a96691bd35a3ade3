//! Parameter lists: loading and checking them, `ncchannel check` on them, and a TwinCAT CNC
//! installation's own lists starting the channel.

#[path = "../support/mod.rs"]
mod support;

mod check_params;
mod ext_vars;
mod installation;
mod params;
mod techno;
