//! Receiving NC data split into programs by start/end markers (SINUMERIK Manage MyPrograms
//! style): the splitter state machine, the name lines, and the atomic program writer.
//!
//! Data flows `Read` → [`Splitter`] (pure, any chunk sizes) → [`ProgramSink`] →
//! [`ProgramWriter`] (temp file, fsync, rename). [`transfer`] ties them to a file, standard
//! input or one TCP connection; [`listen`] takes a port's connections.

pub(crate) mod control_line;
pub(crate) mod error;
pub(crate) mod listen;
pub mod markers;
pub mod splitter;
pub mod stop;
pub mod temp_files;
pub(crate) mod transfer;
pub(crate) mod writer;

pub use control_line::{NameInfo, NameKind, RejectedName, SinumerikName};
pub use error::DncError;
pub use listen::{Listener, TransferResult};
pub use markers::{Anchor, Markers, Mode, LINE_WINDOW, MAX_MARKERS};
pub use splitter::{ProgramEnd, ProgramSink, ProgramStart, SplitSummary, Splitter};
pub use stop::{StopLevel, StopRequest};
pub use transfer::{
    receive, receive_limited, receive_stream, Limit, TransferEnd, TransferLimits, TransferReport,
};
pub use writer::{Disposition, NameTemplate, ProgramWriter, ReceivedProgram, WriterConfig};
