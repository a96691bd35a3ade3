//! Where NC text comes from: the data-streaming interface, the program files found through the
//! search paths (large ones read by a loader thread), and the file cache.

pub(crate) mod cache;
pub(crate) mod loader;
pub(crate) mod packets;
pub(crate) mod store;
pub(crate) mod stream;
