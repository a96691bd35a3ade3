//! The served devices behind one TCP port, as a TwinCAT router has them: which AMS port is
//! which task, and the map of every object served (generated into docs/ads.md).
//!
//! | AMS port | task | module |
//! |---|---|---|
//! | 551 | GEO (interpolator, HLD) | [`super::geo`] |
//! | 552 | SDA (NC variables) | [`super::sda`] |
//! | 553 | COM (platform, channel, axis objects; description table) | [`super::com`] |
//! | 851 | PLC runtime 1 (HLI symbols) | [`super::hli`] |
//! | 10000 | TwinCAT system service (state, extended state, state control, device info) | [`super::system`] |
//!
//! Port numbers: TwinSharp `CNC.cs` (`Connect(target, 551/552/553/851)`); 553 is also the
//! documented COM port (ISG kernel docs 348532363). Any other port answers AMS error 6.
//! Every port serves the ADS sum commands ([`super::sum`]) over its own objects.

use std::fmt::Write as _;
use std::sync::Arc;

use super::backend::{CncBackend, Op};
use super::description::ObjectInfo;
use super::hli::Hli;
use super::result::AdsResult;
use super::sda::Sda;
use super::sum::{self, Port};
use super::system::{System, SystemChange};
use super::{com, geo, hli, sda, system};

/// AMS port of the CNC's COM task.
pub(crate) const PORT_CNC_COM: u16 = com::PORT;
/// Every AMS port served.
pub(crate) const PORTS: [u16; 5] = [geo::PORT, sda::PORT, com::PORT, hli::PORT, system::PORT];

/// Channel index group base (index-based, as the ISG SDK and `ncchannel stream` use it).
pub(crate) const GROUP_CHANNEL: u32 = com::GROUP_CHANNEL_INDEX;
/// Channel index group base, logical addressing; same objects.
pub const GROUP_CHANNEL_NEW: u32 = com::GROUP_CHANNEL;

/// Offsets in a channel's COM group that `ncchannel stream` and the tests name.
pub mod offset {
    /// `mc_program_stream_w`: write one packet of whole CR LF lines (≤ 992 bytes).
    pub const STREAM: u32 = 0x90;
    /// `mcm_active_r`: active mode and state, two i32 (8 bytes).
    pub const MODE_STATE: u32 = 0x103;
    /// `mcm_command_to_mode_w`.
    pub const COMMAND_MODE: u32 = 0x104;
    /// `mcm_command_to_state_w`.
    pub const COMMAND_STATE: u32 = 0x105;
    /// `mcm_command_parameter_w`: the program name.
    pub const COMMAND_PROGRAM: u32 = 0x108;
    /// `mcm_automatic_stop_w`: feed hold.
    pub const HOLD: u32 = 0x136;
    /// `mcm_automatic_resume_w`.
    pub const RESUME: u32 = 0x137;
    /// `mcm_automatic_reset_w`.
    pub const RESET: u32 = 0x13C;
    /// `mc_error_message_r`: STRING(1330).
    pub const ERROR_MESSAGE: u32 = 0x26;
    /// `mc_block_count_r`: NC lines decoded since the start, u32.
    pub const BLOCK_COUNT: u32 = 0x0D;
    /// `mc_command_feedrate_override_w`: u16 in 0.1 % (1000 = 100 %).
    pub const FEED_OVERRIDE: u32 = 0x09;
    /// `ncc_stream_fill_r`: u32 used bytes + u32 free bytes.
    pub const STREAM_FILL: u32 = 0x8001;
    /// `ncc_blocks_executed_r`: u64 blocks that took effect since the channel started.
    pub const BLOCK_COUNTER: u32 = 0x8002;
    /// `ncc_positions_mm_r`: one f64 (mm) per axis.
    pub const POSITIONS: u32 = 0x8003;
}

/// The four tasks and the system service over one backend.
pub struct Devices {
    backend: Arc<dyn CncBackend>,
    hli: Hli,
    sda: Sda,
    system: System,
}

impl Devices {
    pub fn new(backend: Arc<dyn CncBackend>) -> Self {
        Devices {
            hli: Hli::new(Arc::clone(&backend)),
            sda: Sda::new(Arc::clone(&backend)),
            system: System::new(),
            backend,
        }
    }

    /// Whether a request that reached the server at `arrived` is answered "busy" without
    /// asking the runtime ([`CncBackend::overdue`]).
    pub fn overdue(&self, arrived: std::time::Instant) -> bool {
        self.backend.overdue(arrived)
    }

    /// Register `watch` (its encoder filled in here) to be evaluated in the cycle when
    /// `(port, group, offset)` is one object of a table (a COM object, a GEO element, an SDA
    /// variable handle, an HLI symbol handle), with the encoder a Read of it runs; false for
    /// what is read whole (the description table, the uploads, the system service) or when
    /// the machine did not take it: the caller samples by reading then.
    pub fn watch(
        &self,
        port: u16,
        group: u32,
        offset: u32,
        length: u32,
        make: impl FnOnce(crate::machine::watch::Encode) -> crate::machine::watch::Watch,
    ) -> bool {
        let Some(encode) = self.encoder(port, group, offset, length) else {
            return false;
        };
        let slot = crate::machine::watch::WatchSlot::new(make(super::backend::in_cycle(encode)));
        matches!(
            self.backend.call(1, Op::Watch(slot)),
            Ok(super::backend::Reply::Done)
        )
    }

    /// The encoder a Read of `(port, group, offset)` runs, for the objects of a table.
    fn encoder(
        &self,
        port: u16,
        group: u32,
        offset: u32,
        length: u32,
    ) -> Option<super::backend::ObjectEncoder> {
        let b = self.backend.as_ref();
        match port {
            com::PORT => com::encoder(&mut super::backend::Live::new(b), group, offset, length),
            geo::PORT => geo::encoder(b.channel_count(), &self.hli, group, offset, length),
            sda::PORT => self.sda.encoder(group, offset, length),
            hli::PORT => self.hli.encoder(group, offset, length),
            _ => return None,
        }
        .ok()
    }

    /// Whether `port` is served (else the router answers AMS error 6).
    pub fn serves(port: u16) -> bool {
        PORTS.contains(&port)
    }

    /// Whether `port` is there now: the system service always, the runtime's ports (CNC
    /// tasks, PLC runtime) only while the system is in RUN (a TwinCAT system in CONFIG or
    /// STOP has no runtime; the router answers AMS error 6 for them).
    pub fn serves_now(&self, port: u16) -> bool {
        Self::serves(port) && (port == system::PORT || self.system.running())
    }

    /// ReadState on `port`: (ADS state, device state). The system service answers the
    /// system's state, the PLC runtime its own (RUN or STOP), the CNC tasks RUN: they run
    /// while the system does.
    pub fn read_state(&self, port: u16) -> (u16, u16) {
        match port {
            system::PORT => (self.system.state(), 0),
            hli::PORT => (self.hli.ads_state(), 0),
            _ => (system::state::RUN, 0),
        }
    }

    /// WriteControl `ads_state` on `port` (the device state is kept: 0). docs/ads.md
    /// ("ADS state control") says what each does on each port:
    /// - 10000: RESET restarts the system (every channel reset, the PLC runtime afresh in
    ///   RUN, the restart index counts), RUN starts a system that is not running, CONFIG and
    ///   RECONFIG enter CONFIG and STOP stops (every channel reset; the runtime ports answer
    ///   AMS error 6 until a restart);
    /// - 851: RUN, STOP, RESET of the PLC runtime ([`Hli::control`]); CONFIG/RECONFIG go to
    ///   the system service (there is one configuration mode for all tasks);
    /// - 553 and the other CNC tasks: RESET and STOP reset every channel (the program stops,
    ///   READY; the task keeps running, so its state stays RUN), RUN changes nothing,
    ///   CONFIG/RECONFIG go to the system service.
    ///
    /// 0x706 for a state the port does not take.
    pub fn write_control(&self, port: u16, ads_state: u16) -> Result<(), AdsResult> {
        use system::state;
        let system_wide =
            port == system::PORT || matches!(ads_state, state::CONFIG | state::RECONFIG);
        if system_wide {
            return match self.system.control(ads_state)? {
                Some(SystemChange::Restart) => {
                    self.reset_channels();
                    self.hli.restart();
                    Ok(())
                }
                Some(SystemChange::Halt) => {
                    self.reset_channels();
                    Ok(())
                }
                None => Ok(()),
            };
        }
        match (port, ads_state) {
            (hli::PORT, _) => self.hli.control(ads_state),
            (_, state::RESET | state::STOP) => {
                self.reset_channels();
                Ok(())
            }
            (_, state::RUN) => Ok(()),
            _ => Err(AdsResult::INVALID_DATA),
        }
    }

    /// NC reset of every channel (`mcm_automatic_reset_w`'s reset): programs end, motion
    /// stops, READY. A channel the runtime cannot reach now is left as it is (logged).
    fn reset_channels(&self) {
        let b = self.backend.as_ref();
        for ch in 1..=b.channel_count() {
            if let Err(e) = b.command(ch, Op::Reset) {
                log::warn!("ADS state control: channel {ch} not reset: {e}");
            }
        }
    }

    /// ADS Read.
    pub fn read(
        &self,
        port: u16,
        group: u32,
        offset: u32,
        length: u32,
    ) -> Result<Vec<u8>, AdsResult> {
        let b = self.backend.as_ref();
        match port {
            com::PORT => com::read(b, group, offset, length),
            geo::PORT => geo::read(b, &self.hli, group, offset, length),
            sda::PORT => self.sda.read(group, offset, length),
            hli::PORT => self.hli.read(group, offset, length),
            system::PORT => self.system.read(group, offset, length),
            _ => Err(AdsResult::SERVICE_NOT_SUPPORTED),
        }
    }

    /// ADS Write.
    pub fn write(&self, port: u16, group: u32, offset: u32, data: &[u8]) -> Result<(), AdsResult> {
        match port {
            com::PORT => com::write(self.backend.as_ref(), &self.hli, group, offset, data),
            geo::PORT => geo::write(self.backend.as_ref(), &self.hli, group, offset, data),
            sda::PORT => self.sda.write(group, offset, data),
            hli::PORT => self.hli.write(group, offset, data),
            system::PORT => Err(AdsResult::INVALID_GROUP),
            _ => Err(AdsResult::SERVICE_NOT_SUPPORTED),
        }
    }

    /// ADS ReadWrite.
    pub fn read_write(
        &self,
        port: u16,
        group: u32,
        offset: u32,
        read_length: u32,
        data: &[u8],
    ) -> Result<Vec<u8>, AdsResult> {
        if sum::is_sum(group) {
            let on = OnPort {
                devices: self,
                port,
            };
            return sum::execute(&on, group, offset, read_length, data);
        }
        match port {
            // COM objects have no ReadWrite service.
            com::PORT => Err(AdsResult::ACCESS_DENIED),
            geo::PORT => geo::read_write(self.backend.as_ref(), group, offset, read_length, data),
            sda::PORT => self.sda.read_write(group, offset, read_length, data),
            hli::PORT => self.hli.read_write(group, offset, read_length, data),
            system::PORT => self.system.read(group, offset, read_length),
            _ => Err(AdsResult::SERVICE_NOT_SUPPORTED),
        }
    }

    /// ReadDeviceInfo's (major, minor, build, name) on `port`; `None` for the CNC tasks,
    /// which answer with ncchannel's own (the server's default).
    pub fn device_info(port: u16) -> Option<(u8, u8, u16, &'static str)> {
        system::device_info(port)
    }

    /// Every object served for channel 1, port by port: the object map.
    pub fn objects(&self) -> Result<Vec<ObjectInfo>, AdsResult> {
        let b = self.backend.as_ref();
        let mut all = com::objects(b, 1)?;
        all.extend(geo::objects(1));
        all.extend(sda::objects(1));
        all.extend(self.hli.objects()?);
        Ok(all)
    }
}

/// One port's objects, as the sub-requests of a sum command reach them.
struct OnPort<'d> {
    devices: &'d Devices,
    port: u16,
}

impl Port for OnPort<'_> {
    fn read(&self, group: u32, offset: u32, length: u32) -> Result<Vec<u8>, AdsResult> {
        self.devices.read(self.port, group, offset, length)
    }

    fn write(&self, group: u32, offset: u32, data: &[u8]) -> Result<(), AdsResult> {
        self.devices.write(self.port, group, offset, data)
    }

    fn read_write(
        &self,
        group: u32,
        offset: u32,
        read_length: u32,
        data: &[u8],
    ) -> Result<Vec<u8>, AdsResult> {
        self.devices
            .read_write(self.port, group, offset, read_length, data)
    }
}

/// The object map as Markdown: one table per port, every object with group, offset, type,
/// size, access, unit and source. docs/ads.md holds this text for a one-channel, three-axis
/// machine (`ncchannel objects --markdown`; a test keeps the file current).
pub fn markdown(objects: &[ObjectInfo]) -> String {
    let mut out = String::new();
    for (port, title) in [
        (com::PORT, "COM task, AMS port 553"),
        (geo::PORT, "GEO task, AMS port 551"),
        (sda::PORT, "SDA task, AMS port 552"),
        (
            hli::PORT,
            "PLC HLI, AMS port 851 (symbols by name; handle = value-by-handle offset)",
        ),
    ] {
        let _ = writeln!(out, "### {title}\n");
        if port == hli::PORT {
            out.push_str("| symbol | type | bytes | source |\n|---|---|---|---|\n");
        } else {
            out.push_str(
                "| name | group | offset | type | bytes | access | unit | source |\n|---|---|---|---|---|---|---|---|\n",
            );
        }
        for o in objects.iter().filter(|o| o.port == port) {
            if port == hli::PORT {
                let _ = writeln!(
                    out,
                    "| `{}` | {} | {} | {} |",
                    o.name,
                    o.ty.name(),
                    o.size,
                    o.source
                );
            } else {
                let _ = writeln!(
                    out,
                    "| `{}` | 0x{:X} | 0x{:X} | {} | {} | {} | {} | {} |",
                    o.name,
                    o.group,
                    o.offset,
                    o.ty.name(),
                    o.size,
                    o.access.letters(),
                    o.unit,
                    o.source
                );
            }
        }
        out.push('\n');
    }
    out
}

/// A channel count and nothing else: what resolving a COM channel object needs.
struct Channels(u16);

impl super::backend::Source for Channels {
    fn channel_count(&self) -> u16 {
        self.0
    }

    fn status(&mut self, _: u16) -> Result<&super::backend::Status, super::backend::DeviceError> {
        Err(super::backend::DeviceError::NotReady)
    }

    fn call(
        &mut self,
        _: u16,
        _: Op,
    ) -> Result<super::backend::Reply, super::backend::DeviceError> {
        Err(super::backend::DeviceError::NotReady)
    }
}

/// `bench --load cycle --notifications`: a 1 ms on-change watch of channel `ch`'s
/// `ncc_blocks_executed_r` with the object table's own encoder, counting its samples into
/// `samples` where the ADS server queues a frame.
pub(crate) fn bench_watch(
    ch: u16,
    samples: Arc<std::sync::atomic::AtomicU64>,
) -> Option<crate::machine::watch::Watch> {
    let group = com::GROUP_CHANNEL + u32::from(ch);
    let encode = com::encoder(&mut Channels(ch), group, offset::BLOCK_COUNTER, 8).ok()?;
    Some(bench_counting(super::backend::in_cycle(encode), samples))
}

/// `bench --load cycle --notifications N --notify-on hli`: `count` 1 ms on-change watches of
/// the channels' HLI `…mode_and_state.state_r` in turn, with the symbol table's own encoder,
/// counting their samples into `samples`.
pub(crate) fn bench_hli_watches(
    channels: u16,
    count: usize,
    samples: &Arc<std::sync::atomic::AtomicU64>,
) -> Vec<crate::machine::watch::Watch> {
    hli::bench_encoders(usize::from(channels), count)
        .into_iter()
        .map(|e| bench_counting(super::backend::in_cycle(e), Arc::clone(samples)))
        .collect()
}

/// A 1 ms on-change watch with `encode`, counting its samples into `samples`.
fn bench_counting(
    encode: crate::machine::watch::Encode,
    samples: Arc<std::sync::atomic::AtomicU64>,
) -> crate::machine::watch::Watch {
    use crate::machine::watch::{Delivery, Watch};
    Watch {
        cycle: std::time::Duration::from_millis(1),
        on_change: true,
        encode,
        deliver: Box::new(move |bytes: &[u8]| {
            std::hint::black_box(bytes);
            samples.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            Delivery::Sent
        }),
        alive: Arc::new(std::sync::atomic::AtomicBool::new(true)),
    }
}
