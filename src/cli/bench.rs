//! `ncchannel bench`: the runtime in real time under a streaming load, against a bare
//! spin_sleep loop measured in the same run, so lateness is compared on the same machine at
//! the same moment.
//!
//! The load is real: `--channels N` channels, each streaming its own endless generated
//! program at full rate through its own stream interface, decoder and motion (the soak cycle
//! without faults, so the invariants are checked too). The synthetic [`StreamingLoad`] (a
//! feeder and a stream buffer only) stays for the stream benchmark and tests.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use crossbeam_channel::Sender;

use crate::feeder::{Feeder, FeederError};
use crate::report::event::{EventBuffer, EventKind, EventLog};
use crate::report::stats::Histogram;
use crate::runtime::{bare_loop, Clock, Cycle, Flow, Runtime, Tick};
use crate::soak::driver::{Slot, SoakCycle};
use crate::soak::feed::{FeederSpec, SoakFeeder, Source};
use crate::soak::generator::{Generator, ProgramSpec};
use crate::soak::rng::SplitMix64;
use crate::soak::scenario::Faults;
use crate::source::stream::{
    StreamBuffer, StreamWriteError, MAX_PROGRAM_STREAM_INPUT_SIZE, MAX_PROGRAM_STREAM_SIZE,
};

#[derive(Debug, clap::Args)]
pub struct BenchArgs {
    /// Cycle time in microseconds.
    #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u64).range(10..=1_000_000))]
    pub period_us: u64,
    /// Seconds to run the runtime (the bare loop runs as long again, the two alternating
    /// about every second).
    #[arg(long, default_value_t = 5.0)]
    pub seconds: f64,
    /// Channels streaming at full rate (a 992-byte write attempt each tick), each with its
    /// own generated program, stream, decoder and motion.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=12))]
    pub channels: u32,
    /// Start-up list the channels are built from (its channels are reused in turn when it
    /// has fewer than --channels).
    #[arg(long, default_value = "params/soak/startup4.lis")]
    pub params: PathBuf,
    /// Seed of the generated programs and packet sizes.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write a lateness histogram (runtime and bare loop) as SVG here.
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

/// A stream write from another thread, answered in the tick that serves it.
#[derive(Debug)]
pub struct WriteRequest {
    pub packet: Vec<u8>,
    pub reply: Sender<Result<(), StreamWriteError>>,
}

/// A channel-shaped synthetic load: a feeder writes into a [`StreamBuffer`], a reader takes
/// the buffered data out as one segment every `take_every` ticks and counts its lines.
/// Write and segment events go to the event buffer, as a channel's would.
pub struct StreamingLoad {
    feeder: Feeder,
    stream: StreamBuffer,
    segment: Vec<u8>,
    take_every: u64,
    looping: bool,
    lines: u64,
    events: EventBuffer,
    log: EventLog,
}

impl StreamingLoad {
    /// `looping`: start the text over when it has all been read, instead of stopping.
    pub fn new(
        text: Vec<u8>,
        packet_max: usize,
        take_every: u64,
        looping: bool,
        log: EventLog,
    ) -> Result<Self, FeederError> {
        Ok(StreamingLoad {
            feeder: Feeder::new(text, packet_max, 1, false)?,
            stream: StreamBuffer::new(),
            segment: Vec::with_capacity(MAX_PROGRAM_STREAM_SIZE),
            take_every: take_every.max(1),
            looping,
            lines: 0,
            events: log.buffer(),
            log,
        })
    }

    /// Lines read out of the stream so far.
    pub fn lines(&self) -> u64 {
        self.lines
    }

    pub fn stream(&self) -> &StreamBuffer {
        &self.stream
    }

    /// Write out the event log and join its writer.
    pub fn finish(self) -> std::io::Result<u64> {
        self.log.finish()
    }

    fn write(&mut self, packet_len: usize, r: Result<(), StreamWriteError>, tick: &Tick) {
        if self.events.enabled() {
            let code = r.err().and_then(|e| e.isg_code());
            self.events.push(
                tick,
                1,
                EventKind::Write {
                    bytes: packet_len as u64,
                    ok: r.is_ok(),
                    code,
                },
            );
        }
    }
}

impl Cycle for StreamingLoad {
    type Request = WriteRequest;

    fn serve(&mut self, req: WriteRequest, tick: &Tick) {
        let r = self.stream.write(&req.packet);
        self.write(req.packet.len(), r, tick);
        // A writer that stopped waiting for its answer is no concern of the tick.
        let _ = req.reply.send(r);
    }

    fn step(&mut self, tick: &Tick) -> Flow {
        if let Some(packet) = self.feeder.poll(tick.index) {
            let r = self.stream.write(packet);
            let len = packet.len();
            self.feeder.result(r.is_ok());
            self.write(len, r, tick);
        }
        if tick.index.is_multiple_of(self.take_every) {
            let n = self.stream.take_segment(&mut self.segment);
            if n > 0 {
                self.lines += self.segment.iter().filter(|&&b| b == b'\n').count() as u64;
                self.events
                    .push(tick, 1, EventKind::Segment { bytes: n as u64 });
            }
        }
        self.events.flush_to(&mut self.log);
        if self.feeder.done() && self.stream.is_empty() {
            if !self.looping {
                return Flow::Stop;
            }
            self.feeder.rewind();
        }
        Flow::Continue
    }
}

/// `lines` NC lines of a milling-like contour: linear and circular moves with feeds, comments
/// and the odd M function, LF-terminated.
pub fn generated_program(lines: usize) -> Vec<u8> {
    let mut s = String::with_capacity(lines * 32);
    s.push_str("%bench\nN1 G90 G17 G71 F2000 ; synthetic load\n");
    for i in 2..lines {
        let x = (i * 37 % 2000) as f64 / 10.0;
        let y = (i * 91 % 1500) as f64 / 10.0;
        let line = match i % 7 {
            0 => format!("N{i} G02 X{x:.3} Y{y:.3} I5.000 J0\n"),
            3 => format!(
                "N{i} G01 X{x:.3} Y{y:.3} F{} (feed change)\n",
                1000 + i % 500
            ),
            5 => format!("N{i} M08\n"),
            _ => format!("N{i} G01 X{x:.3} Y{y:.3} Z-{:.2}\n", (i % 5) as f64 * 0.25),
        };
        s.push_str(&line);
    }
    s.push_str("M30\n");
    s.into_bytes()
}

fn print_hist(name: &str, h: &Histogram) {
    println!(
        "{name:<20} p50 {:>8.2}  p99 {:>8.2}  p99.9 {:>8.2}  max {:>9.2}  (n = {})",
        h.quantile_us(0.5),
        h.quantile_us(0.99),
        h.quantile_us(0.999),
        h.max_us(),
        h.count()
    );
}

/// `n` channels built from the start-up list, each fed its own endless generated program by
/// a client writing 992-byte packets every tick: the soak cycle without faults.
pub fn streaming_channels(
    params: &Path,
    n: u32,
    seed: u64,
) -> Result<(SoakCycle, Duration), String> {
    let config = crate::params::load(params).map_err(|e| {
        e.diagnostics()
            .iter()
            .map(|d| d.render())
            .collect::<Vec<_>>()
            .join("\n")
    })?;
    if config.channels.is_empty() {
        return Err("the start-up list has no channel".into());
    }
    let axes = crate::setup::axes(&config).map_err(|e| e.to_string())?;
    let mut rng = SplitMix64::new(seed);
    let mut slots = Vec::new();
    for i in 0..n {
        let cc = &config.channels[i as usize % config.channels.len()];
        let mut settings =
            crate::setup::channel_settings(&config, cc).map_err(|e| e.to_string())?;
        settings.number = i + 1;
        let program = settings
            .streaming_prog
            .clone()
            .ok_or_else(|| format!("{}: streaming is off", cc.list_path.display()))?;
        let mut r = rng.fork(u64::from(i));
        let feeder = SoakFeeder::new(
            FeederSpec {
                packet_bytes: [MAX_PROGRAM_STREAM_INPUT_SIZE, MAX_PROGRAM_STREAM_INPUT_SIZE],
                ..FeederSpec::default()
            },
            r.fork(2),
            Source::Generated(Generator::new(ProgramSpec::default(), r.fork(1))),
        );
        let channel = crate::channel::Channel::new(settings, false);
        slots.push(Slot::new(channel, program, feeder, &axes, r.fork(3)));
    }
    let period = Duration::from_micros(config.runtime.cycle_period_us.max(1));
    Ok((
        SoakCycle::new(slots, Faults::default(), Vec::new(), None),
        period,
    ))
}

pub fn execute(args: BenchArgs) -> ExitCode {
    let usage = |msg: String| {
        eprintln!("ncchannel bench: {msg}");
        ExitCode::from(super::exit::USAGE)
    };
    if !(args.seconds.is_finite() && args.seconds > 0.0 && args.seconds <= 3600.0) {
        return usage("--seconds must be in (0, 3600]".into());
    }
    let params = super::run::locate(&args.params);
    let (cycle, _) = match streaming_channels(&params, args.channels, args.seed) {
        Ok(c) => c,
        Err(e) => return usage(format!("{}: {e}", params.display())),
    };
    let period = Duration::from_micros(args.period_us);
    let ticks = ((args.seconds * 1e6) / args.period_us as f64)
        .ceil()
        .max(1.0) as u64;
    let slices = (ticks / (1_000_000 / args.period_us).max(1)).clamp(1, 3600);
    println!(
        "bench: period {} µs, {} channels streaming, {ticks} ticks runtime + {ticks} ticks bare spin_sleep loop, alternating in {slices} slices",
        args.period_us, args.channels
    );
    // Runtime and bare loop alternate in slices of about a second, so a change of load on a
    // shared machine (another build starting) hits both alike.
    let mut bare = Histogram::new();
    let (mut rt, _tx) = Runtime::new(cycle, period, Clock::RealTime);
    let mut wall = Duration::ZERO;
    for k in 0..slices {
        let n = ticks * (k + 1) / slices - ticks * k / slices;
        bare.merge(&bare_loop(period, n));
        wall += rt.run(Some(n)).wall;
    }
    let (cycle, stats) = rt.into_inner();

    println!("all figures in µs");
    print_hist("tick work", &stats.work);
    print_hist("tick lateness", &stats.lateness);
    print_hist("bare loop lateness", &bare);
    let bare_p99 = bare.quantile_us(0.99);
    let ratio = if bare_p99 > 0.0 {
        stats.lateness.quantile_us(0.99) / bare_p99
    } else {
        f64::NAN
    };
    println!("overruns             {}", stats.overruns);
    println!("lateness p99 ratio runtime / bare loop: {ratio:.2} (target ≤ 1.2)");
    let blocks = cycle.total_blocks;
    let (mut ok, mut rejected, mut bytes) = (0, 0, 0);
    for s in &cycle.slots {
        let c = s.feeder.counters();
        ok += c.writes_ok;
        rejected += c.writes_rejected;
        bytes += c.bytes;
    }
    let wall = wall.as_secs_f64();
    println!(
        "load: {blocks} blocks executed ({:.0}/s), {ok} writes ok, {rejected} rejected (buffer full), {:.1} MB streamed in {wall:.2} s",
        blocks as f64 / wall.max(1e-9),
        bytes as f64 / 1e6,
    );
    let t = &cycle.tallies;
    let violations = t.order.violations + t.errors.violations + t.limits.violations;
    if violations > 0 {
        println!("invariant violations during the bench: {violations}");
    }
    if let Some(p) = &args.plot {
        let svg = crate::soak::plot::lateness_svg(&stats.lateness, &bare, period);
        if let Err(e) = std::fs::write(p, svg) {
            return usage(format!("--plot {}: {e}", p.display()));
        }
        println!("histogram written to {}", p.display());
    }
    ExitCode::from(super::exit::OK)
}
