//! Program streaming: the stream buffer, the channel's stream interface, what a streamed program
//! may do, `ncchannel stream` behind a full buffer, exactly-once writes, the built-in feeder.

#[path = "../support/mod.rs"]
mod support;

mod channel_stream;
mod decoder_stream;
mod exactly_once;
mod feeder;
mod stream;
mod stream_rate;
mod stream_stall;
