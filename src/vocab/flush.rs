//! `#FLUSH` (ISG programming manual, "#FLUSH"): what the parser reads, the block queue
//! carries, the planner acts on and the event log names.

/// `#FLUSH` variants; in the event log `plain`, `continue`, `wait`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FlushKind {
    /// `#FLUSH`: release all held blocks, stop at the end of the last.
    #[serde(rename = "plain")]
    Stop,
    /// `#FLUSH CONTINUE`: release all, no stop if the next block comes in time.
    Continue,
    /// `#FLUSH WAIT`: decoding waits until interpolation has emptied the channel.
    Wait,
}
