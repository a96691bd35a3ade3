//! Parameter lists: the ISG list format, typed start-up and channel lists, runtime.toml.
//!
//! The rest of the program calls [`load`] with the start-up list and gets a [`Config`], or a
//! [`ParamError`] listing every problem; `ncchannel check` calls [`check_list_file`].

pub mod axes;
pub mod catalog;
pub mod channel;
pub mod config;
pub mod decoder;
pub mod error;
pub mod error_texts;
pub mod list;
pub mod runtime;
pub mod search_path;
pub mod startup;
pub mod tools;
pub mod value;
pub mod zero_offsets;

pub use config::{check_list_file, load, ChannelConfig, Config, RUNTIME_FILE};
pub use decoder::{CacheSettings, DecoderSettings, FCT_USE_CACHED_FILES};
pub use error::ParamError;
pub use list::{Entry, ParamList, Value, ValueKind};
pub use runtime::{AdsConfig, AxisConfig, AxisKind, RuntimeConfig};
pub use search_path::{SearchPath, MAIN_PROGRAMS, SUBROUTINES};
