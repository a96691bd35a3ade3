//! `serve --soak`: the soak's faults and invariants around the real channels while external
//! ADS clients stream into them. Wraps the [`Machine`] as the runtime's cycle: every request
//! passes through it (an accepted stream write makes its lines owed), faults are injected at
//! the start of each tick, and the executed stream blocks are checked after it.

use std::collections::VecDeque;
use std::path::Path;
use std::time::Duration;

use super::driver::{MachineDoor, SoakChannel, SoakCounters, Tallies};
use super::feed::Owed;
use super::invariants::{resident_kib, Verdict};
use super::rng::SplitMix64;
use super::scenario::{Faults, Scenario};
use crate::channel::AxisLimits;
use crate::machine::{Machine, Op, Reply, Request};
use crate::runtime::{Clock, Cycle, Flow, Tick};

/// How long a channel stays READY after an injected reset before its streaming program
/// restarts: longer than the 200 ms default cycle of an on-change notification in
/// TwinCAT.Ads (Beckhoff InfoSys, `NotificationSettings.Default`) and Node ads-client, with
/// 50 ms for the server's sampling, so a client watching mode and state sees every reset.
pub const READY_HOLD: Duration = Duration::from_millis(250);

/// Reset notices kept until `serve --soak` prints them; more in one print interval are
/// counted, not kept.
const MAX_PENDING_NOTICES: usize = 64;

/// A reset the soak injected (or made after a channel error), as `serve --soak` announces it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ResetNotice {
    pub channel: u32,
    /// The tick of the reset.
    pub tick: u64,
    /// After a channel error, rather than by the fault plan.
    pub after_error: bool,
    /// Accepted lines the reset dropped before they ran.
    pub lines_dropped: u64,
    /// The tick at which the program restarts (READY until then).
    pub restart_tick: Option<u64>,
}

/// Scenario tables that describe the built-in client; an external client has none of them.
pub(crate) const CLIENT_KEYS: [&str; 5] = ["feeder", "program", "channel", "length", "clock"];

/// Load a scenario for external clients: the soak's format, its client keys refused by name.
pub(crate) fn load_external(path: &Path) -> Result<Scenario, String> {
    let shown = path.display();
    let bytes = crate::bounded::read_file(path, super::scenario::MAX_SCENARIO_BYTES)
        .map_err(|e| format!("{shown}: {e}"))?;
    let text = String::from_utf8(bytes).map_err(|_| format!("{shown}: not UTF-8 text"))?;
    check_external(&text).map_err(|m| format!("{shown}: {m}"))?;
    // The length is serve's --seconds; the soak's parser wants one, so it gets a dummy.
    let mut s = Scenario::parse(&format!("{text}\n[length]\nticks = 1\n"))
        .map_err(|m| format!("{shown}: {m}"))?;
    s.dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    s.path = path.to_path_buf();
    s.validate().map_err(|m| format!("{shown}: {m}"))?;
    if s.faults.reset_every_blocks.is_some() {
        return Err(format!(
            "{shown}: [faults] reset_every_blocks needs the built-in client; use reset_every_ticks"
        ));
    }
    Ok(s)
}

/// Refuse the scenario keys that make no sense against external clients, naming them.
pub(crate) fn check_external(text: &str) -> Result<(), String> {
    let doc: toml::Table = text.parse().map_err(|e| format!("{e}"))?;
    let bad: Vec<&str> = CLIENT_KEYS
        .iter()
        .copied()
        .filter(|k| doc.contains_key(*k))
        .collect();
    if bad.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "{} describe(s) the built-in client and make(s) no sense with external clients (serve --soak takes params, seed, [faults], [invariants]; the length is --seconds)",
            bad.join(", ")
        ))
    }
}

/// One channel under external clients: the driver core, and what the clients owe.
struct Watch {
    core: SoakChannel,
    /// Lines of accepted writes not yet executed, and the stream bytes of this epoch.
    owed: VecDeque<Owed>,
    epoch_bytes: u64,
}

impl Watch {
    /// A new stream: what was owed is dropped by the reset or program end; offsets restart.
    fn new_epoch(owed: &mut VecDeque<Owed>, epoch_bytes: &mut u64) {
        owed.clear();
        *epoch_bytes = 0;
    }
}

/// The machine under external clients, with faults and invariant checks.
pub struct Supervised {
    machine: Machine,
    faults: Faults,
    expected_errors: Vec<u32>,
    /// One generator for every channel's faults, drawn in channel order.
    rng: SplitMix64,
    watches: Vec<Watch>,
    tallies: Tallies,
    planned: bool,
    /// Resets not yet announced, and how many did not fit.
    notices: VecDeque<ResetNotice>,
    notices_lost: u64,
}

impl Supervised {
    /// Observation of executed stream blocks is turned on here, through each channel's door.
    /// `programs`: per channel, its streaming program (`streaming_prog_file`), restarted
    /// after a reset; `axes`: the soft limits positions are checked against.
    pub fn new(
        mut machine: Machine,
        scenario: &Scenario,
        axes: &[AxisLimits],
        programs: Vec<Option<String>>,
    ) -> Self {
        let n = machine.channels().len() as u32;
        let tick0 = Tick::first(Duration::ZERO, Clock::RealTime);
        for ch in 1..=n {
            machine.apply(&tick0, ch, Op::ObserveStreamBlocks(true));
        }
        let mut programs = programs.into_iter();
        Supervised {
            machine,
            faults: scenario.faults.clone(),
            expected_errors: scenario.invariants.expected_errors.clone(),
            rng: SplitMix64::new(scenario.seed),
            watches: (1..=n)
                .map(|channel| Watch {
                    core: SoakChannel::new(channel, programs.next().flatten(), axes)
                        .with_rising_numbers(),
                    owed: VecDeque::new(),
                    epoch_bytes: 0,
                })
                .collect(),
            tallies: Tallies::default(),
            planned: false,
            notices: VecDeque::new(),
            notices_lost: 0,
        }
    }

    /// The resets since the last call, oldest first, and how many more were not kept.
    pub fn take_notices(&mut self) -> (Vec<ResetNotice>, u64) {
        let lost = std::mem::take(&mut self.notices_lost);
        (self.notices.drain(..).collect(), lost)
    }

    pub(crate) fn into_machine(self) -> Machine {
        self.machine
    }

    /// Each channel's counters so far.
    pub fn counters(&self) -> Vec<SoakCounters> {
        self.watches
            .iter()
            .zip(self.machine.channels())
            .map(|(w, c)| w.core.report(c))
            .collect()
    }

    /// Stream blocks checked so far, all channels.
    pub fn blocks(&self) -> u64 {
        self.watches.iter().map(|w| w.core.counters.blocks).sum()
    }

    /// The verdicts so far (`growth`: resident set after warm-up, KiB).
    pub(crate) fn verdicts(&self, growth: Option<i64>, slack_kib: u64) -> Vec<Verdict> {
        self.tallies
            .verdicts(self.blocks(), &self.expected_errors, growth, slack_kib)
    }
}

/// Lines of a packet: (offset in packet, N, whether it must yield a block). A numbered line
/// must; an unnumbered one (a comment, a blank line) may yield none.
fn packet_lines(data: &[u8]) -> Vec<(usize, Option<u32>)> {
    let mut out = Vec::new();
    let mut start = 0;
    while start < data.len() {
        let end = memchr::memchr(b'\n', &data[start..]).map_or(data.len(), |i| start + i + 1);
        out.push((start, line_number(&data[start..end])));
        start = end;
    }
    out
}

fn line_number(line: &[u8]) -> Option<u32> {
    let s = std::str::from_utf8(line).ok()?.trim_start();
    let rest = s.strip_prefix('N').or_else(|| s.strip_prefix('n'))?;
    let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
    digits.parse().ok()
}

impl Cycle for Supervised {
    type Request = Request;

    fn serve(&mut self, req: Request, tick: &Tick) {
        if !req.claim.take() {
            return;
        }
        let w = (req.channel as usize).wrapping_sub(1);
        let Some(watch) = self.watches.get_mut(w) else {
            let reply = self.machine.apply(tick, req.channel, req.op);
            let _ = req.reply.send(reply);
            return;
        };
        let reply = match req.op {
            Op::WriteStream(_) if watch.core.rejecting(tick.index) => {
                watch.core.counters.writes_skipped += 1;
                Reply::Stream(Err(crate::machine::StreamWriteError::Full { free: 0 }))
            }
            Op::WriteStream(data) => {
                let len = data.len() as u64;
                let lines = packet_lines(&data);
                let r = self.machine.apply(tick, req.channel, Op::WriteStream(data));
                let c = &mut watch.core.counters;
                if r == Reply::Stream(Ok(())) {
                    c.writes_ok += 1;
                    c.bytes += len;
                    for (off, n) in lines {
                        c.lines_accepted += 1;
                        watch.owed.push_back(Owed {
                            offset: watch.epoch_bytes + off as u64,
                            n,
                            must_run: n.is_some(),
                        });
                    }
                    watch.epoch_bytes += len;
                } else {
                    c.writes_rejected += 1;
                }
                r
            }
            Op::Reset => {
                // A reset the client commanded drops the buffer: nothing written is owed.
                let r = self.machine.apply(tick, req.channel, Op::Reset);
                Watch::new_epoch(&mut watch.owed, &mut watch.epoch_bytes);
                watch.core.new_epoch();
                r
            }
            op => self.machine.apply(tick, req.channel, op),
        };
        let _ = req.reply.send(reply);
    }

    fn step(&mut self, tick: &Tick) -> Flow {
        if !self.planned {
            self.planned = true;
            let hold_ticks = READY_HOLD
                .as_nanos()
                .div_ceil(tick.period.as_nanos().max(1));
            for w in &mut self.watches {
                w.core.plan(&mut self.rng, &self.faults, tick.index);
                w.core
                    .set_ready_hold(u64::try_from(hold_ticks).unwrap_or(u64::MAX));
            }
        }
        for (i, w) in self.watches.iter_mut().enumerate() {
            let Some(mut door) = MachineDoor::new(&mut self.machine, i as u32 + 1) else {
                continue;
            };
            let before = (w.core.counters.resets, w.core.counters.error_resets);
            let mut dropped = 0u64;
            let (owed, epoch_bytes) = (&mut w.owed, &mut w.epoch_bytes);
            w.core
                .faults(&mut self.rng, &self.faults, tick, &mut door, &mut |_| {
                    dropped += owed.len() as u64;
                    Watch::new_epoch(owed, epoch_bytes)
                });
            let c = &mut w.core.counters;
            if (c.resets, c.error_resets) != before {
                c.lines_dropped += dropped;
                let notice = ResetNotice {
                    channel: i as u32 + 1,
                    tick: tick.index,
                    after_error: c.error_resets != before.1,
                    lines_dropped: dropped,
                    restart_tick: w.core.ready_held_until(),
                };
                if self.notices.len() < MAX_PENDING_NOTICES {
                    self.notices.push_back(notice);
                } else {
                    self.notices_lost += 1;
                }
            }
        }
        let flow = self.machine.step(tick);
        for (i, w) in self.watches.iter_mut().enumerate() {
            let Some(mut door) = MachineDoor::new(&mut self.machine, i as u32 + 1) else {
                continue;
            };
            w.core.check(
                tick,
                &mut door,
                &mut w.owed,
                &mut self.tallies,
                &self.expected_errors,
            );
        }
        flow
    }

    fn take_clock_stopped(&mut self) -> Duration {
        self.machine.take_clock_stopped()
    }

    fn record_work(&mut self, work: Duration) {
        self.machine.record_work(work);
    }
}

/// Resident set now, KiB (for the memory invariant of `serve --soak`).
pub fn resident() -> Option<u64> {
    resident_kib()
}
