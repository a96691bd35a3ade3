//! The channel's ISG mode and state machine: HLI mode and state numbers, which commands each
//! state accepts, and the `state` events a change writes.

use super::hmi::Hmi;
use super::log::ChannelLog;
use super::CommandError;
use crate::runtime::Tick;
use crate::vocab::mode::{Mode, State};

/// Mode and state as the HLI shows them (`mc_active_mode_r`, `mc_active_state_r`).
#[derive(Debug)]
pub(super) struct Isg {
    /// Operation mode: automatic, manual, MDI … (command 0x104).
    mode: Mode,
    /// Channel state: READY, SELECTED, ACTIVE, HOLD, ERROR … (command 0x105).
    state: State,
}

/// What a command to state (0x105) asks the channel to do, once the state machine allows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum StateCommand {
    /// ACTIVE from HOLD: go on.
    Resume,
    /// ACTIVE from READY or SELECTED in automatic mode: start the command parameter's program.
    Start,
    /// Nothing to do: ACTIVE while ACTIVE, SELECTED while READY.
    Nothing,
    /// HOLD: feed hold.
    Hold,
    /// READY: NC reset.
    Reset,
}

impl Isg {
    pub(super) fn new() -> Self {
        Isg {
            mode: Mode::Automatic,
            state: State::Ready,
        }
    }

    pub(super) fn mode(&self) -> Mode {
        self.mode
    }

    pub(super) fn state(&self) -> State {
        self.state
    }

    /// A program runs (ACTIVE or HOLD): the tick decodes and moves.
    pub(super) fn running(&self) -> bool {
        matches!(self.state, State::Active | State::Hold)
    }

    /// The refusal of a command the current mode and state do not allow.
    pub(super) fn busy(&self) -> CommandError {
        CommandError::Busy {
            mode: self.mode,
            state: self.state,
        }
    }

    /// Enter `state`; a change writes a `state` event. Leaving ACTIVE/HOLD releases the HMI's
    /// feed hold: no program runs, so nothing is held.
    pub(super) fn set_state(
        &mut self,
        tick: &Tick,
        state: State,
        hmi: &mut Hmi,
        log: &mut ChannelLog,
    ) {
        if !matches!(state, State::Active | State::Hold) {
            // No program runs: nothing is held.
            hmi.release_feed_hold();
        }
        if self.state != state {
            self.state = state;
            log.state(tick, self.mode, self.state);
        }
    }

    /// Command to mode (0x104): refused while a program runs.
    pub(super) fn command_mode(
        &mut self,
        tick: &Tick,
        v: i32,
        log: &mut ChannelLog,
    ) -> Result<(), CommandError> {
        let mode = Mode::from_i32(v).ok_or(CommandError::InvalidValue(v))?;
        if self.running() {
            return Err(self.busy());
        }
        if self.mode != mode {
            self.mode = mode;
            log.state(tick, self.mode, self.state);
        }
        Ok(())
    }

    /// Command to state (0x105): ACTIVE starts (or resumes), HOLD holds, READY resets; what the
    /// channel is to do, or why not.
    pub(super) fn command_state(&self, v: i32) -> Result<StateCommand, CommandError> {
        let state = State::from_i32(v).ok_or(CommandError::InvalidValue(v))?;
        match state {
            State::Active => match self.state {
                State::Hold => Ok(StateCommand::Resume),
                State::Ready | State::Selected if self.mode == Mode::Automatic => {
                    Ok(StateCommand::Start)
                }
                State::Active => Ok(StateCommand::Nothing),
                _ => Err(self.busy()),
            },
            State::Hold => Ok(StateCommand::Hold),
            State::Ready => Ok(StateCommand::Reset),
            // PROCESS_SELECTED, the state a mode change leads to (TwinSharp
            // `OperationModeManager.Reset()` asks for it with the old mode): a channel that
            // runs nothing is there already (READY: its program is selected).
            State::Selected if matches!(self.state, State::Ready | State::Selected) => {
                Ok(StateCommand::Nothing)
            }
            _ => Err(self.busy()),
        }
    }

    /// A main program may start only from READY or SELECTED; it runs in automatic mode (the
    /// mode changes without an event of its own: the start's `state` event shows it).
    pub(super) fn enter_automatic(&mut self) -> Result<(), CommandError> {
        if !matches!(self.state, State::Ready | State::Selected) {
            return Err(self.busy());
        }
        self.mode = Mode::Automatic;
        Ok(())
    }
}
