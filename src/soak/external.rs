//! `serve --soak`: the soak's faults and invariants around the real channels while external
//! ADS clients stream into them. Wraps the [`Machine`] as the runtime's cycle: every request
//! passes through it (an accepted stream write makes its lines owed), faults are injected at
//! the start of each tick, and the executed stream blocks are checked after it.

use std::collections::VecDeque;
use std::path::Path;

use serde::Serialize;

use super::driver::draw;
use super::feed::Owed;
use super::invariants::{check_blocks, resident_kib, Checksum, Tally, Verdict};
use super::rng::SplitMix64;
use super::scenario::{Faults, Scenario};
use crate::channel::State;
use crate::machine::{Machine, Op, Reply, Request};
use crate::runtime::{Cycle, Flow, Tick};

/// Scenario tables that describe the built-in client; an external client has none of them.
const CLIENT_KEYS: [&str; 5] = ["feeder", "program", "channel", "length", "clock"];

/// Load a scenario for external clients: the soak's format, its client keys refused by name.
pub fn load_external(path: &Path) -> Result<Scenario, String> {
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
pub fn check_external(text: &str) -> Result<(), String> {
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

/// The fault schedule of one channel, in ticks.
#[derive(Debug, Default)]
struct Schedule {
    reset_at: Option<u64>,
    hold_at: Option<u64>,
    hold_until: Option<u64>,
    override_at: Option<u64>,
    reject_at: Option<u64>,
    reject_until: Option<u64>,
}

/// Counters of one channel, as the report shows them.
#[derive(Debug, Clone, Default, Serialize)]
pub struct ExternalCounters {
    pub channel: u32,
    /// Stream writes accepted, and their lines (now owed).
    pub writes_accepted: u64,
    pub lines_accepted: u64,
    /// Writes refused by a forced rejection (answered 0x708 without touching the buffer).
    pub writes_forced_rejected: u64,
    /// Stream blocks executed and checked.
    pub blocks: u64,
    pub resets: u64,
    pub error_resets: u64,
    pub restarts: u64,
    pub holds: u64,
    pub overrides: u64,
    pub forced_rejections: u64,
}

struct Watch {
    /// The last N executed this epoch: a numbered line is a client's line once, so an N not
    /// above it is a line run again (or out of order), even when the client wrote it twice.
    last_n: Option<u32>,
    owed: VecDeque<Owed>,
    epoch_bytes: u64,
    schedule: Schedule,
    counters: ExternalCounters,
    sum: Checksum,
}

/// The machine under external clients, with faults and invariant checks.
pub struct Supervised {
    machine: Machine,
    faults: Faults,
    expected_errors: Vec<u32>,
    rng: SplitMix64,
    watches: Vec<Watch>,
    order: Tally,
    errors: Tally,
    limits: Tally,
    /// Soft limits per axis letter (mm): min, max.
    soft_limits: Vec<(char, f64, f64)>,
    /// Per channel: its streaming program (`streaming_prog_file`), restarted after a reset.
    programs: Vec<Option<String>>,
    /// Executed stream blocks of the channel being checked (reused).
    executed: Vec<crate::channel::ExecutedBlock>,
    planned: bool,
}

impl Supervised {
    /// `machine`'s channels must observe their stream blocks; this turns it on.
    pub fn new(
        mut machine: Machine,
        scenario: &Scenario,
        soft_limits: Vec<(char, f64, f64)>,
        programs: Vec<Option<String>>,
    ) -> Self {
        let n = machine.channels().len() as u32;
        for ch in 1..=n {
            if let Some(c) = machine.channel_mut(ch) {
                c.observe_stream_blocks(true);
            }
        }
        Supervised {
            machine,
            faults: scenario.faults.clone(),
            expected_errors: scenario.invariants.expected_errors.clone(),
            rng: SplitMix64::new(scenario.seed),
            watches: (1..=n)
                .map(|channel| Watch {
                    last_n: None,
                    owed: VecDeque::new(),
                    epoch_bytes: 0,
                    schedule: Schedule::default(),
                    counters: ExternalCounters {
                        channel,
                        ..Default::default()
                    },
                    sum: Checksum::default(),
                })
                .collect(),
            order: Tally::default(),
            errors: Tally::default(),
            limits: Tally::default(),
            soft_limits,
            programs,
            executed: Vec::new(),
            planned: false,
        }
    }

    pub fn machine_mut(&mut self) -> &mut Machine {
        &mut self.machine
    }

    pub fn into_machine(self) -> Machine {
        self.machine
    }

    pub fn counters(&self) -> Vec<ExternalCounters> {
        self.watches.iter().map(|w| w.counters.clone()).collect()
    }

    /// Order, errors and limits verdicts so far.
    pub fn verdicts(&self) -> Vec<Verdict> {
        let blocks: u64 = self.watches.iter().map(|w| w.counters.blocks).sum();
        vec![
            self.order.verdict(
                "every accepted line executed exactly once, in order, between resets",
                Some(format!("{blocks} blocks checked")),
            ),
            self.errors.verdict(
                "no channel error but the expected ones",
                Some(format!("expected: {:?}", self.expected_errors)),
            ),
            self.limits
                .verdict("positions within the axis soft limits", None),
        ]
    }

    fn plan(&mut self, w: usize, now: u64) {
        let f = &self.faults;
        let s = &mut self.watches[w].schedule;
        s.reset_at = draw(&mut self.rng, now, f.reset_every_ticks);
        s.hold_at = draw(&mut self.rng, now, f.hold_every_ticks);
        s.override_at = draw(&mut self.rng, now, f.override_every_ticks);
        s.reject_at = draw(&mut self.rng, now, f.reject_every_ticks);
    }

    /// A new stream: what was owed is dropped by the reset or program end; offsets restart.
    fn restart(&mut self, w: usize, tick: &Tick) {
        let watch = &mut self.watches[w];
        watch.owed.clear();
        watch.epoch_bytes = 0;
        watch.last_n = None;
        let ch = watch.counters.channel;
        let prog = self.programs.get(w).cloned().flatten();
        if let Some(c) = self.machine.channel_mut(ch) {
            let _ = c.drain_executed().count();
            if let Some(prog) = prog {
                // A failed start raises its channel error, which the error check then sees.
                let _ = c.start(tick, &prog);
            }
        }
    }

    fn faults(&mut self, tick: &Tick) {
        let t = tick.index;
        for w in 0..self.watches.len() {
            let ch = self.watches[w].counters.channel;
            let Some(state) = self.machine.channels().get(w).map(|c| c.state()) else {
                continue;
            };
            let reset_due = self.watches[w].schedule.reset_at.is_some_and(|r| t >= r);
            if reset_due || state == State::Error {
                if let Some(c) = self.machine.channel_mut(ch) {
                    if state == State::Error {
                        let code = c.last_error().map(|e| e.code).unwrap_or(0);
                        if !self.expected_errors.contains(&code) {
                            let msg = c.last_error().map(|e| e.msg.clone()).unwrap_or_default();
                            self.errors
                                .violate(|| format!("channel {ch}: error {code} {msg}"));
                        }
                        self.watches[w].counters.error_resets += 1;
                    } else {
                        self.watches[w].counters.resets += 1;
                    }
                    c.reset(tick);
                }
                let f = self.faults.reset_every_ticks;
                self.watches[w].schedule.reset_at = draw(&mut self.rng, t, f);
                self.watches[w].schedule.hold_until = None;
                self.restart(w, tick);
            } else if state == State::Ready {
                self.watches[w].counters.restarts += 1;
                self.restart(w, tick);
            }
            let f = self.faults.clone();
            let Some(c) = self.machine.channel_mut(ch) else {
                continue;
            };
            let watch = &mut self.watches[w];
            let s = &mut watch.schedule;
            if s.hold_until.is_some_and(|u| t >= u) {
                s.hold_until = None;
                c.resume(tick);
            } else if s.hold_at.is_some_and(|h| t >= h) {
                s.hold_at = draw(&mut self.rng, t, f.hold_every_ticks);
                if c.state() == State::Active {
                    c.hold(tick);
                    s.hold_until = Some(t + self.rng.range(f.hold_ticks[0], f.hold_ticks[1]));
                    watch.counters.holds += 1;
                }
            }
            if s.override_at.is_some_and(|o| t >= o) {
                s.override_at = draw(&mut self.rng, t, f.override_every_ticks);
                let [lo, hi] = f.override_pct;
                let pct = (self.rng.range_f64(lo, hi) * 10.0).round() / 10.0;
                if c.set_override(pct.clamp(0.0, 200.0)).is_ok() {
                    watch.counters.overrides += 1;
                }
            }
            if s.reject_at.is_some_and(|r| t >= r) {
                s.reject_at = draw(&mut self.rng, t, f.reject_every_ticks);
                s.reject_until = Some(t + self.rng.range(f.reject_ticks[0], f.reject_ticks[1]));
                watch.counters.forced_rejections += 1;
            }
        }
    }

    fn check(&mut self) {
        for (w, watch) in self.watches.iter_mut().enumerate() {
            let ch = watch.counters.channel;
            let Some(c) = self.machine.channel_mut(ch) else {
                continue;
            };
            self.executed.clear();
            self.executed.extend(c.drain_executed());
            for b in &self.executed {
                if let Some(n) = b.n {
                    if watch.last_n.is_some_and(|last| n <= last) {
                        let last = watch.last_n.unwrap_or(0);
                        self.order.violate(|| {
                            format!("channel {ch}: N{n} executed after N{last} (a line run twice or out of order)")
                        });
                    }
                    watch.last_n = Some(n);
                }
            }
            watch.counters.blocks += check_blocks(
                ch,
                &mut watch.owed,
                self.executed.drain(..),
                &mut self.order,
                &mut watch.sum,
            );
            for (axis, pos) in c.axis_positions() {
                if let Some(&(_, lo, hi)) = self.soft_limits.iter().find(|l| l.0 == axis) {
                    if !(lo..=hi).contains(&pos) {
                        self.limits
                            .violate(|| format!("channel {}: {axis} = {pos:.3} mm", w + 1));
                    }
                }
            }
        }
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
        let rejecting = self
            .watches
            .get(w)
            .and_then(|x| x.schedule.reject_until)
            .is_some_and(|u| tick.index < u);
        let reply = match req.op {
            Op::WriteStream(_) if rejecting => {
                self.watches[w].counters.writes_forced_rejected += 1;
                Reply::Stream(Err(crate::source::stream::StreamWriteError::Full {
                    free: 0,
                }))
            }
            Op::WriteStream(data) => {
                let r = self
                    .machine
                    .apply(tick, req.channel, Op::WriteStream(data.clone()));
                if let (Reply::Stream(Ok(())), Some(watch)) = (&r, self.watches.get_mut(w)) {
                    watch.counters.writes_accepted += 1;
                    for (off, n) in packet_lines(&data) {
                        watch.counters.lines_accepted += 1;
                        watch.owed.push_back(Owed {
                            offset: watch.epoch_bytes + off as u64,
                            n,
                            must_run: n.is_some(),
                        });
                    }
                    watch.epoch_bytes += data.len() as u64;
                }
                r
            }
            Op::Reset => {
                // A reset the client commanded drops the buffer: nothing written is owed.
                let r = self.machine.apply(tick, req.channel, Op::Reset);
                if let Some(watch) = self.watches.get_mut(w) {
                    watch.owed.clear();
                    watch.epoch_bytes = 0;
                    watch.last_n = None;
                }
                r
            }
            op => self.machine.apply(tick, req.channel, op),
        };
        let _ = req.reply.send(reply);
    }

    fn step(&mut self, tick: &Tick) -> Flow {
        if !self.planned {
            self.planned = true;
            for w in 0..self.watches.len() {
                self.plan(w, tick.index);
            }
        }
        self.faults(tick);
        let flow = self.machine.step(tick);
        self.check();
        flow
    }
}

/// Resident set now, KiB (for the memory invariant of `serve --soak`).
pub fn resident() -> Option<u64> {
    resident_kib()
}
