//! The TwinCAT system service on AMS port 10000: the system's ADS state (RUN, CONFIG, STOP)
//! as ReadState and the extended state read (index group 0xF0) answer it, WriteControl that
//! restarts the system or sets it to CONFIG, and ReadDeviceInfo naming the system service.
//!
//! Port number: `ADS_RESERVED_PORTS.SystemService` (ads-client), `AMSPORT_R3_SYSSERV` (AdsLib
//! `AdsDef.h`); pyads `read_state()` and `adstool <netid> state` read it there. ADS states:
//! Beckhoff InfoSys "ADSSTATE" (`ADSSTATE_RESET` 2, `RUN` 5, `STOP` 6, `CONFIG` 15,
//! `RECONFIG` 16; AdsLib `AdsDef.h`). ads-client `setTcSystemToConfig` sends RECONFIG and
//! `setTcSystemToRun`/`restartTcSystem` send RESET to this port; `readTcSystemExtendedState`
//! reads 16 bytes of group 0xF0 (ads state, device state, restart index, TwinCAT version,
//! revision, build, platform, OS type, flags; ads-client `readTcSystemExtendedState`).

use std::sync::atomic::{AtomicU16, Ordering};

use super::result::AdsResult;

/// AMS port of the TwinCAT system service.
pub const PORT: u16 = 10000;

pub(crate) use super::symbols::ads_state as state;

/// Index group of the system service's extended state (ads-client
/// `readTcSystemExtendedState`: `readRaw(240, 0, 16)`).
pub(crate) const GROUP_EXTENDED_STATE: u32 = 0xF0;
/// Bytes of the extended state.
const EXTENDED_STATE_BYTES: usize = 16;

/// TwinCAT 3.1 build 4024, as ReadDeviceInfo names it.
const TWINCAT_3_1: (u8, u8, u16) = (3, 1, 4024);
/// Platform id in the extended state: not public in the sources named above; ncchannel
/// answers 0 (unknown) rather than claim a Beckhoff platform.
const PLATFORM_UNKNOWN: u8 = 0;
/// OS type in the extended state: 0 (unknown), for the same reason.
const OS_UNKNOWN: u8 = 0;

/// What ReadDeviceInfo answers on `port`, for the TwinCAT ports (the CNC tasks answer with
/// ncchannel's own name and version): the system service and the PLC runtime name
/// themselves as TwinCAT 3.1 does (`TwinCAT System`; `Plc30 App`, the PLC runtime's device
/// name that pyads' and ads-client's documentation show), version 3.1 of TwinCAT 3.
pub(crate) fn device_info(port: u16) -> Option<(u8, u8, u16, &'static str)> {
    let (major, minor, build) = TWINCAT_3_1;
    match port {
        PORT => Some((major, minor, build, "TwinCAT System")),
        super::hli::PORT => Some((major, minor, build, "Plc30 App")),
        _ => None,
    }
}

/// What a WriteControl to the system service asks of the tasks behind it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SystemChange {
    /// Start (again): the channels are reset, the PLC runtime starts afresh in RUN.
    Restart,
    /// CONFIG or STOP: the channels are reset; the runtime ports are gone until a restart.
    Halt,
}

/// The system service's state: RUN, CONFIG or STOP, and how often it was restarted.
#[derive(Debug)]
pub(crate) struct System {
    state: AtomicU16,
    restarts: AtomicU16,
}

impl System {
    pub(crate) fn new() -> Self {
        System {
            state: AtomicU16::new(state::RUN),
            restarts: AtomicU16::new(0),
        }
    }

    /// The system's ADS state.
    pub(crate) fn state(&self) -> u16 {
        self.state.load(Ordering::SeqCst)
    }

    /// Whether the runtime ports (CNC tasks, PLC runtime) exist: only in RUN, as a TwinCAT
    /// system in CONFIG has no runtime.
    pub(crate) fn running(&self) -> bool {
        self.state() == state::RUN
    }

    /// WriteControl `ads_state`: RESET restarts (also from RUN: TwinCAT's restart), RUN starts
    /// a system that is not running, CONFIG and RECONFIG enter CONFIG, STOP stops. What the
    /// tasks must do, or `None` when nothing changes; 0x706 for other states.
    pub(crate) fn control(&self, ads_state: u16) -> Result<Option<SystemChange>, AdsResult> {
        let (next, change) = match ads_state {
            state::RESET => (state::RUN, SystemChange::Restart),
            state::RUN if self.running() => return Ok(None),
            state::RUN => (state::RUN, SystemChange::Restart),
            state::CONFIG | state::RECONFIG => (state::CONFIG, SystemChange::Halt),
            state::STOP => (state::STOP, SystemChange::Halt),
            _ => return Err(AdsResult::INVALID_DATA),
        };
        if change == SystemChange::Restart {
            self.restarts.fetch_add(1, Ordering::SeqCst);
        }
        self.state.store(next, Ordering::SeqCst);
        Ok(Some(change))
    }

    /// Group 0xF0: the extended state (ads state, device state 0, restart index, TwinCAT
    /// version, revision and build, platform, OS type, flags 0, reserved).
    pub(crate) fn read(&self, group: u32, offset: u32, length: u32) -> Result<Vec<u8>, AdsResult> {
        if group != GROUP_EXTENDED_STATE {
            return Err(AdsResult::INVALID_GROUP);
        }
        if offset != 0 {
            return Err(AdsResult::INVALID_OFFSET);
        }
        if (length as usize) < EXTENDED_STATE_BYTES {
            return Err(AdsResult::INVALID_SIZE);
        }
        let (version, revision, build) = TWINCAT_3_1;
        let mut out = Vec::with_capacity(EXTENDED_STATE_BYTES);
        out.extend_from_slice(&self.state().to_le_bytes());
        out.extend_from_slice(&0u16.to_le_bytes());
        out.extend_from_slice(&self.restarts.load(Ordering::SeqCst).to_le_bytes());
        out.extend_from_slice(&[version, revision]);
        out.extend_from_slice(&build.to_le_bytes());
        out.extend_from_slice(&[PLATFORM_UNKNOWN, OS_UNKNOWN]);
        out.resize(EXTENDED_STATE_BYTES, 0);
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn config_halts_and_reset_restarts_counting_restarts() {
        let s = System::new();
        assert_eq!(s.control(state::RUN), Ok(None), "RUN while RUN: nothing");
        assert_eq!(s.control(state::RECONFIG), Ok(Some(SystemChange::Halt)));
        assert_eq!((s.state(), s.running()), (state::CONFIG, false));
        let ext = s.read(GROUP_EXTENDED_STATE, 0, 16).unwrap();
        assert_eq!(&ext[0..6], &[15, 0, 0, 0, 0, 0]);
        assert_eq!(s.control(state::RESET), Ok(Some(SystemChange::Restart)));
        let ext = s.read(GROUP_EXTENDED_STATE, 0, 16).unwrap();
        assert_eq!(&ext[0..10], &[5, 0, 0, 0, 1, 0, 3, 1, 0xB8, 0x0F]);
        assert_eq!(s.control(99), Err(AdsResult::INVALID_DATA));
        assert_eq!(
            s.read(GROUP_EXTENDED_STATE, 0, 8),
            Err(AdsResult::INVALID_SIZE)
        );
        assert_eq!(s.read(0xF100, 0, 16), Err(AdsResult::INVALID_GROUP));
    }
}
