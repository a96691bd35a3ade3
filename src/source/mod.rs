//! Where NC text comes from: the data-streaming interface, the program files found through the
//! search paths, and the file cache.

pub mod cache;
pub mod packets;
pub mod store;
pub mod stream;
