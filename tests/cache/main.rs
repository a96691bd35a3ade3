//! The file cache (`#CACHE`) through the channel, in virtual time.

#[path = "../support/mod.rs"]
mod support;

mod cache;
mod cache_large;
