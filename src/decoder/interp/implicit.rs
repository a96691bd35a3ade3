//! The implicit subroutine calls' state in the running program (P-CHAN-00118, P-CHAN-00119,
//! P-CHAN-00187, P-CHAN-00252): which have been called, and ends held back for them.

use crate::queue::BlockInfo;

/// A program end (M02/M30) or return (M17/M29) held back while an implicit subroutine runs
/// before it: applied when the frame stack is back at `depth`.
#[derive(Debug, Clone)]
pub(super) struct HeldEnd {
    pub(super) m: u32,
    pub(super) info: BlockInfo,
    pub(super) depth: usize,
}

/// Where the running program stands with its implicit subroutine calls.
#[derive(Debug, Clone, Default)]
pub(super) struct ImplicitState {
    /// The start subroutine (P-CHAN-00119) is still to be called.
    pub(super) start_pending: bool,
    /// The end subroutine (P-CHAN-00252) has been called.
    pub(super) end_called: bool,
    /// Depth of the running M6 subroutine's frame: an M6 inside it is an ordinary M function,
    /// as the kernel does not call the tool change from the tool change.
    pub(super) m6_depth: Option<usize>,
    /// Ends held back, innermost last (at most one per frame).
    pub(super) held: Vec<HeldEnd>,
}

impl ImplicitState {
    pub(super) fn at_start(calls: &crate::params::channel::ImplicitSubroutines) -> Self {
        ImplicitState {
            start_pending: calls.at_start.is_some(),
            ..Default::default()
        }
    }
}
