//! Parameter lists: the ISG list format, typed start-up and channel lists, runtime.toml.
//!
//! The rest of the program calls [`load`] with the start-up list and gets a [`Config`], or a
//! [`ParamError`] listing every problem; `ncchannel check` calls [`check_list_file`].

pub(crate) mod axes;
pub(crate) mod catalog;
pub(crate) mod channel;
pub mod config;
pub(crate) mod decoder;
pub(crate) mod error;
pub mod error_texts;
pub mod ext_vars;
pub mod list;
pub(crate) mod runtime;
pub(crate) mod search_path;
pub mod shipped;
pub(crate) mod startup;
pub(crate) mod techno;
pub(crate) mod tools;
pub(crate) mod value;
pub(crate) mod zero_offsets;

pub use config::{check_list_file, load, ChannelConfig, Config, RUNTIME_FILE};
pub use decoder::{CacheSettings, DecoderSettings, FCT_USE_CACHED_FILES};
pub use error::ParamError;
pub use list::{Entry, ParamList, Value, ValueKind};
pub use runtime::{AdsConfig, AxisConfig, AxisKind, RuntimeConfig};
pub use search_path::{SearchPath, MAIN_PROGRAMS, SUBROUTINES};
