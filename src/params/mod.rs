//! Parameter lists: the ISG list format, typed start-up and channel lists, runtime.toml.
