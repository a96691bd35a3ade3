//! Notification watches evaluated in the cycle: after every tick the machine encodes each
//! active watch's object with its table's encoder, reading the tick itself as the encoder's
//! [`Source`] (each channel's status built once per tick), compares it with the bytes
//! it last delivered (on change) or checks its cycle (cyclic), and hands a sample to the
//! watch's sink, which queues it on the owning connection's bounded send queue and never
//! waits. TwinCAT checks notification handles in the task cycle (Beckhoff InfoSys, ADS
//! "AdsAddDeviceNotification": the server checks the variable every cycle time), so a 1 ms
//! on-change handle sees every change of a value that changes every tick, and a cyclic one
//! samples on its tick, without a read through the runtime's request queue.
//!
//! A watch is registered once through the request queue ([`Op::Watch`]) and ends when its
//! owner drops the shared `alive` flag (no request): registration is a push, removal a flag,
//! and the tick's work grows only with the number of active watches, at most [`MAX_WATCHES`].

use std::sync::atomic::Ordering;
use std::time::Duration;

use super::{Op, Reply, Status};
pub use crate::channel::door::{Deliver, Delivery, DeviceError, Encode, Source, Watch, WatchSlot};
use crate::runtime::Tick;

/// Watches the machine evaluates at most; one more is refused (the ADS server's 1024
/// handles over all connections, `vocab::ams::DEFAULT_MAX_NOTIFICATIONS_TOTAL`).
pub const MAX_WATCHES: usize = crate::vocab::ams::DEFAULT_MAX_NOTIFICATIONS_TOTAL;

struct Active {
    w: Watch,
    last: Option<Vec<u8>>,
    next_tick: u64,
}

/// The machine's active watches.
#[derive(Default)]
pub(crate) struct Watches {
    list: Vec<Active>,
    /// Per channel, the status of the tick being evaluated (filled on first use).
    statuses: Vec<Option<Box<Status>>>,
}

impl Watches {
    /// Take the watch out of `slot` and keep it; false when [`MAX_WATCHES`] are active or the
    /// slot was empty.
    pub(crate) fn add(&mut self, slot: &WatchSlot) -> bool {
        if self.list.len() >= MAX_WATCHES {
            return false;
        }
        let Some(w) = slot.take() else {
            return false;
        };
        self.list.push(Active {
            w,
            last: None,
            next_tick: 0,
        });
        true
    }

    /// No watch is active: the machine skips the evaluation.
    pub(crate) fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// Evaluate every watch due at `tick`; `apply` answers a read-only request of channel
    /// `ch` in this tick (a status is asked at most once per channel per tick).
    pub(crate) fn evaluate(
        &mut self,
        tick: &Tick,
        channels: usize,
        mut apply: impl FnMut(u32, Op) -> Reply,
    ) {
        if self.list.is_empty() {
            return;
        }
        self.statuses.clear();
        self.statuses.resize_with(channels, || None);
        let period_ns = tick.period.as_nanos().max(1);
        let mut source = InTick {
            statuses: &mut self.statuses,
            apply: &mut apply,
        };
        self.list.retain_mut(|a| {
            if !a.w.alive.load(Ordering::Relaxed) {
                return false;
            }
            if tick.index < a.next_tick {
                return true;
            }
            let Some(bytes) = (a.w.encode)(&mut source) else {
                return true;
            };
            let changed = a.last.as_deref() != Some(bytes.as_slice());
            if a.w.on_change && !changed {
                a.next_tick = tick.index + ticks(a.w.cycle, period_ns);
                return true;
            }
            match (a.w.deliver)(&bytes) {
                Delivery::Sent => {
                    a.last = Some(bytes);
                    a.next_tick = tick.index + ticks(a.w.cycle, period_ns);
                    true
                }
                Delivery::NotYet => true,
                Delivery::Gone => false,
            }
        });
    }
}

/// The tick being evaluated as an encoder's [`Source`]: each channel's status built once,
/// other read-only requests answered at once.
struct InTick<'a, F> {
    statuses: &'a mut [Option<Box<Status>>],
    apply: &'a mut F,
}

impl<F: FnMut(u32, Op) -> Reply> Source for InTick<'_, F> {
    fn channel_count(&self) -> u16 {
        u16::try_from(self.statuses.len()).unwrap_or(u16::MAX)
    }

    fn status(&mut self, ch: u16) -> Result<&Status, DeviceError> {
        let slot = usize::from(ch)
            .checked_sub(1)
            .and_then(|i| self.statuses.get_mut(i))
            .ok_or(DeviceError::NotFound)?;
        if slot.is_none() {
            match (self.apply)(u32::from(ch), Op::Status) {
                Reply::Status(s) => *slot = Some(s),
                _ => return Err(DeviceError::NotReady),
            }
        }
        slot.as_deref().ok_or(DeviceError::NotReady)
    }

    fn call(&mut self, ch: u16, op: Op) -> Result<Reply, DeviceError> {
        match (self.apply)(u32::from(ch), op) {
            Reply::NoChannel => Err(DeviceError::NotFound),
            r => Ok(r),
        }
    }
}

/// Whole ticks in `cycle`, at least one.
fn ticks(cycle: Duration, period_ns: u128) -> u64 {
    u64::try_from(cycle.as_nanos() / period_ns)
        .unwrap_or(u64::MAX)
        .max(1)
}
