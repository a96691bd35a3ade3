//! DNC: `ncchannel receive` into real files, the splitter on every chunking, and the receiver under
//! abuse.

#[path = "../support/mod.rs"]
mod support;

mod dnc_receive;
mod dnc_split;
mod receive_abuse;
mod receive_disk_full;
mod receive_stop;
