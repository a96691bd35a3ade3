//! The TwinCAT system service on AMS port 10000, as far as clients read it before they talk
//! to a runtime: ReadState answers RUN (the server runs while it serves), ReadDeviceInfo
//! names the system service. It has no objects here: every index group is 0x702, so
//! `jisotalo/ads-client`'s extended state read (group 0xF0) fails and it falls back to
//! ReadState, as it does on TwinCAT builds without that service (`setupPlcConnection`).
//!
//! Port number: `ADS_RESERVED_PORTS.SystemService` (ads-client), `AMSPORT_R3_SYSSERV` (AdsLib
//! `AdsDef.h`); pyads `read_state()` and `adstool <netid> state` read it there.

/// AMS port of the TwinCAT system service.
pub const PORT: u16 = 10000;

/// What ReadDeviceInfo answers on `port`, for the TwinCAT ports (the CNC tasks answer with
/// ncchannel's own name and version): the system service and the PLC runtime name
/// themselves as TwinCAT 3.1 does (`TwinCAT System`; `Plc30 App`, the PLC runtime's device
/// name that pyads' and ads-client's documentation show), version 3.1 of TwinCAT 3.
pub(crate) fn device_info(port: u16) -> Option<(u8, u8, u16, &'static str)> {
    const TWINCAT_3_1: (u8, u8, u16) = (3, 1, 4024);
    let (major, minor, build) = TWINCAT_3_1;
    match port {
        PORT => Some((major, minor, build, "TwinCAT System")),
        super::hli::PORT => Some((major, minor, build, "Plc30 App")),
        _ => None,
    }
}
