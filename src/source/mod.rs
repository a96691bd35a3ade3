//! Where NC text comes from: the data-streaming interface (more sources join as they land).

pub mod stream;
