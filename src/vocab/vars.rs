//! The memory budget of a channel's variables (TF5200 diagnosis 20967 "Memory for variables
//! limited", counted per class V.P., V.S., V.E., V.L.): shared by the decoder's variable
//! store, which enforces it, and the V.E. list reader, which refuses a list past it.

/// Bytes each variable class may hold: names, values and [`ENTRY_BYTES`] per entry.
/// 8 MiB is ten of the largest arrays a declaration may make (100,000 values, 0.8 MB);
/// real programs use a few kilobytes.
pub const CLASS_BYTES: usize = 8 << 20;

/// Bookkeeping charged per entry besides its name and values: a hash-table slot (key and
/// value, 56 bytes) and allocator headers, rounded.
pub const ENTRY_BYTES: usize = 64;
