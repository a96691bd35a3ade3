//! ADS result codes: the u32 at the start of every response payload.
//!
//! Device errors travel here (with AMS header error 0); only router-level failures (unknown
//! AMS port, unknown machine) go into the AMS header instead.

use std::fmt;

/// An ADS result code; 0 is success.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct AdsResult(pub u32);

impl AdsResult {
    pub const OK: AdsResult = AdsResult(0);
    /// 0x701: the command (service) is not supported.
    pub(crate) const SERVICE_NOT_SUPPORTED: AdsResult = AdsResult(0x701);
    /// 0x702: no such index group (or channel).
    pub(crate) const INVALID_GROUP: AdsResult = AdsResult(0x702);
    /// 0x703: no such index offset in that group.
    pub(crate) const INVALID_OFFSET: AdsResult = AdsResult(0x703);
    /// 0x704: the object cannot be read (or written) this way.
    pub(crate) const ACCESS_DENIED: AdsResult = AdsResult(0x704);
    /// 0x705: parameter size not correct.
    pub(crate) const INVALID_SIZE: AdsResult = AdsResult(0x705);
    /// 0x706: invalid parameter value (e.g. a stream line without CR LF).
    pub(crate) const INVALID_DATA: AdsResult = AdsResult(0x706);
    /// 0x707: device not ready.
    pub const NOT_READY: AdsResult = AdsResult(0x707);
    /// 0x708: device busy (e.g. the stream buffer cannot take the packet now).
    pub const BUSY: AdsResult = AdsResult(0x708);
    /// 0x70C: not found (e.g. an unknown V.E. variable or notification handle).
    pub(crate) const NOT_FOUND: AdsResult = AdsResult(0x70C);
    /// 0x716 ADSERR_DEVICE_NOMOREHDLS: no more notification handles (per-connection bound
    /// reached). Not 0x710, which is "symbol not found" (Beckhoff ADS return codes).
    pub(crate) const NO_MORE_HANDLES: AdsResult = AdsResult(0x716);
    /// 0x714: invalid notification handle.
    pub(crate) const INVALID_HANDLE: AdsResult = AdsResult(0x714);

    pub fn is_ok(self) -> bool {
        self.0 == 0
    }

    /// A short English name, for logs and client error messages.
    pub fn name(self) -> &'static str {
        match self.0 {
            0 => "no error",
            0x701 => "service not supported",
            0x702 => "invalid index group",
            0x703 => "invalid index offset",
            0x704 => "reading/writing not permitted",
            0x705 => "parameter size not correct",
            0x706 => "invalid parameter value",
            0x707 => "device not ready",
            0x708 => "device busy",
            0x70C => "not found",
            0x716 => "no more notification handles",
            0x714 => "invalid notification handle",
            6 => "target port not found",
            7 => "target machine not found",
            _ => "ADS error",
        }
    }
}

impl fmt::Display for AdsResult {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "0x{:X} ({})", self.0, self.name())
    }
}
