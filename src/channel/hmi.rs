//! What an operator commands besides mode and state: the program to start, block search,
//! single block (its gate into motion), skip levels, optional stop, execution mode, feed hold.

use crate::decoder::{Decoder, SearchTarget};
use crate::motion::Motion;
use crate::queue::{Action, BlockQueue, QueuedBlock};
use crate::vocab::flush::FlushKind;

use super::CommandError;

/// What an HMI commands besides mode and state: the COM task's `mc_command_*` objects
/// (ISG kernel object list, `SamWieHTWG/web-api` `examples/example1-hello-cnc/cnc_objects.csv`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct HmiCommands {
    /// `mc_command_single_block_w`: one block per start.
    pub(crate) single_block: bool,
    /// `mc_command_M01_stop_enable_w`: M01 stops like M00.
    pub(crate) optional_stop: bool,
    /// `mc_command_block_ignore_w`: skip levels 1–10 as the kernel's mask (level n = bit n−1).
    pub(crate) skip_levels: u32,
    /// `mc_command_execution_mode_w`: bit 0 = block search at the next start.
    pub(crate) execution_mode: i32,
    /// `mc_feedhold_channel_w`: the HMI's feed hold holds the running program; only its
    /// release (or an operator start, a reset, the program's end) lets it go.
    pub(crate) feed_hold: bool,
    pub search: SearchCommand,
}

/// Block-search parameters (`mc_cmd_bs_*_w`, TwinSharp `BlockSearch.cs`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SearchCommand {
    /// `mc_cmd_bs_type_w`: 1 file offset, 3 block counter, 4 block number.
    pub kind: u16,
    /// Byte offset in the main program (`mc_command_file_offset_w` / `…pos_start_offset_w`).
    pub(crate) file_offset: i32,
    /// `mc_cmd_bs_intern_block_count_w`.
    pub(crate) block_count: u32,
    /// `mc_cmd_bs_block_number_w`: the N number.
    pub(crate) block_number: u32,
    /// `mc_cmd_bs_distance_prog_start_w`: path distance from the program start where
    /// machining is to continue, 0.1 µm.
    pub(crate) distance_prog_start_tenth_um: f64,
    /// `mc_cmd_bs_covered_distance_w`: share of the found block already covered, 0.1 %
    /// (0..=1000).
    pub(crate) covered_distance_per_mil: f64,
    /// `mc_cmd_bs_auto_return_w`: return to the contour automatically.
    pub(crate) auto_return: bool,
    /// `mc_cmd_bs_deviation_max_w`: largest axis deviation from the continuation position
    /// at the restart, 0.1 µm.
    pub(crate) deviation_max_tenth_um: u32,
    /// `mc_cmd_bs_no_hold_at_restart_w`: resume on the contour without an operator start.
    pub(crate) no_hold_at_restart: bool,
    /// `mc_cmd_bs_breakpoint_position_w`: automatic breakpoint, distance from the program
    /// start, 0.1 µm.
    pub(crate) breakpoint_tenth_um: f64,
}

/// Execution mode bit: block search at the next program start.
pub(crate) const EXECUTION_MODE_BLOCK_SEARCH: i32 = 0x1;

impl SearchCommand {
    /// The decoder's search target this command names, if any.
    pub fn target(&self) -> Option<SearchTarget> {
        match self.kind {
            1 => u64::try_from(self.file_offset)
                .ok()
                .map(SearchTarget::Offset),
            3 => Some(SearchTarget::Counter(u64::from(self.block_count))),
            4 => Some(SearchTarget::BlockNumber(self.block_number)),
            _ => None,
        }
    }
}

/// The operator's commands to the channel and the single-block gate they open.
#[derive(Debug)]
pub(super) struct Hmi {
    /// The `mc_command_*` objects as last written.
    commands: HmiCommands,
    /// Command parameter (0x108): the program `ACTIVE` starts.
    program: Option<String>,
    /// Block search target for the next start (`run --search`).
    search: Option<SearchTarget>,
    /// Single block: the one block motion may take (then a flush that releases it).
    gate: BlockQueue,
    /// Single block: a start allows one more block.
    credit: bool,
    /// Flushes put into the gate whose notes are not program events.
    gate_flushes: usize,
}

impl Hmi {
    pub(super) fn new() -> Self {
        Hmi {
            commands: HmiCommands::default(),
            program: None,
            search: None,
            gate: BlockQueue::new(2),
            credit: false,
            gate_flushes: 0,
        }
    }

    /// HMI commands as last written (the `mc_command_*_r` objects read them back).
    pub(super) fn commands(&self) -> HmiCommands {
        self.commands
    }

    /// Command parameter (0x108): the program to start.
    pub(super) fn set_program(&mut self, name: &str) {
        let name = name.trim_matches(char::from(0)).trim();
        self.program = (!name.is_empty()).then(|| name.to_string());
    }

    /// The command parameter's program, if one is set.
    pub(super) fn program(&self) -> Option<&str> {
        self.program.as_deref()
    }

    /// A start names its program: it becomes the command parameter.
    pub(super) fn starting(&mut self, name: &str) {
        self.program = Some(name.to_string());
    }

    /// Block search target for the next start (`--search`).
    pub(super) fn set_search(&mut self, target: Option<SearchTarget>) {
        self.search = target;
    }

    /// A reset forgets the block search target.
    pub(super) fn forget_search(&mut self) {
        self.search = None;
    }

    /// The block search the next start runs: the one set with `--search`, else the one
    /// commanded in block-search execution mode. Taken once.
    pub(super) fn take_search(&mut self) -> Option<SearchTarget> {
        self.search.take().or_else(|| self.take_commanded_search())
    }

    /// The commanded block search, taken once by a start in block-search execution mode.
    fn take_commanded_search(&mut self) -> Option<SearchTarget> {
        if self.commands.execution_mode & EXECUTION_MODE_BLOCK_SEARCH == 0 {
            return None;
        }
        self.commands.execution_mode &= !EXECUTION_MODE_BLOCK_SEARCH;
        self.commands.search.target()
    }

    /// `mc_command_M01_stop_enable_w`: M01 holds the channel while on.
    pub(super) fn set_optional_stop(&mut self, on: bool, motion: &mut Motion) {
        self.commands.optional_stop = on;
        motion.set_optional_stop(on);
    }

    /// `mc_command_single_block_w`: stop after each block until the next start.
    pub(super) fn set_single_block(&mut self, on: bool) {
        self.commands.single_block = on;
    }

    /// `mc_command_block_ignore_w`: skip levels 1–10 as a mask (level n = bit n−1); the
    /// decoder skips `/n` blocks of a set level from the next line it reads.
    pub(super) fn set_skip_levels(&mut self, mask: u32, decoder: &mut Decoder) {
        let mask = mask & 0x3FF;
        self.commands.skip_levels = mask;
        decoder.set_skip_mask((mask << 1) as u16);
    }

    /// `mc_command_execution_mode_w`: 0 standard, 1 block search at the next start; other
    /// modes (contour visualisation, syntax check, machine lock …) are not modelled.
    pub(super) fn set_execution_mode(&mut self, mode: i32) -> Result<(), CommandError> {
        if mode & !EXECUTION_MODE_BLOCK_SEARCH != 0 {
            return Err(CommandError::InvalidValue(mode));
        }
        self.commands.execution_mode = mode;
        Ok(())
    }

    /// Block-search parameters for the next start in block-search execution mode.
    pub(super) fn set_search_command(&mut self, search: SearchCommand) {
        self.commands.search = search;
    }

    /// `mc_feedhold_channel_w` as last written.
    pub(super) fn feed_hold(&self) -> bool {
        self.commands.feed_hold
    }

    /// The HMI's feed hold takes hold.
    pub(super) fn hold_feed(&mut self) {
        self.commands.feed_hold = true;
    }

    /// The feed hold lets go (its release, a start, a resume, a reset, the program's end).
    pub(super) fn release_feed_hold(&mut self) {
        self.commands.feed_hold = false;
    }

    /// A start or a resume allows the next block in single-block mode.
    pub(super) fn grant_block(&mut self) {
        self.credit = true;
    }

    /// A program starts: one block allowed, the gate empty.
    pub(super) fn restart_single_block(&mut self) {
        self.credit = true;
        self.close_gate();
    }

    /// The gate is emptied (a start, a reset, an error): its blocks and flushes are gone.
    pub(super) fn close_gate(&mut self) {
        self.gate.clear();
        self.gate_flushes = 0;
    }

    /// Blocks in the single-block gate.
    pub(super) fn gate_blocks(&self) -> usize {
        self.gate.len()
    }

    /// A stop flush came out of motion: was it one the gate added (no program event)?
    pub(super) fn gate_flush_done(&mut self) -> bool {
        if self.gate_flushes == 0 {
            return false;
        }
        self.gate_flushes -= 1;
        true
    }

    /// The queue motion takes its blocks from this tick: the block queue, or in single-block
    /// mode (and while the gate still holds blocks) the gate, fed one block per start.
    pub(super) fn blocks_for_motion<'a>(
        &'a mut self,
        queue: &'a mut BlockQueue,
        motion: &Motion,
    ) -> &'a mut BlockQueue {
        if self.commands.single_block || !self.gate.is_empty() {
            if self.commands.single_block {
                self.feed_single_block(queue, motion);
            }
            &mut self.gate
        } else {
            queue
        }
    }

    /// Single block: the block let in is done and no start has allowed another; the channel
    /// holds until the next start.
    pub(super) fn block_done(&self, motion: &Motion) -> bool {
        self.commands.single_block && !self.credit && motion.idle() && self.gate.is_empty()
    }

    /// Single block: let the next decoded block (with its silent second parts) into motion,
    /// once per start, followed by a flush so the planner releases it at once instead of
    /// holding it for its lookahead window.
    fn feed_single_block(&mut self, queue: &mut BlockQueue, motion: &Motion) {
        if !self.credit || !motion.idle() || !self.gate.is_empty() {
            return;
        }
        let Some(first) = queue.pop_front() else {
            return;
        };
        let mut last = first.clone();
        self.gate.push(first);
        while queue.front().is_some_and(|b| b.silent) {
            if let Some(b) = queue.pop_front() {
                last = b.clone();
                self.gate.push(b);
            }
        }
        if !matches!(last.action, Action::Flush(_) | Action::End { .. }) {
            self.gate.push(QueuedBlock {
                info: last.info,
                action: Action::Flush(FlushKind::Stop),
                silent: true,
            });
            self.gate_flushes += 1;
        }
        self.credit = false;
    }
}
