//! The full-rate streaming load of `ncchannel bench` and `benches/soak.rs`: real channels,
//! each fed its own endless generated program, checked by the soak's invariants.

use std::path::Path;
use std::time::Duration;

use super::driver::{Slot, SoakCycle};
use super::feed::{FeederSpec, SoakFeeder, Source};
use super::generator::{Generator, ProgramSpec};
use super::rng::SplitMix64;
use super::scenario::Faults;
use crate::machine::{Machine, StopWhen};
use crate::report::event::EventLog;
use crate::source::loader::Loader;
use crate::source::stream::MAX_PROGRAM_STREAM_INPUT_SIZE;

/// What the load's generated programs hold (`bench --load cycle --mix`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Mix {
    /// Parameter blocks only: blocks that do not move are decoded as fast as they arrive, so
    /// every tick takes about one 992-byte packet per channel: the decoder at full rate.
    #[default]
    Params,
    /// The soak's mix: 0.05 mm moves in random directions, arcs, parameter blocks and M8/M9.
    /// The moves stop at nearly every corner and each M8/M9 waits 20 ms for its
    /// acknowledgement, so a channel runs about 45 blocks a second and its stream stands full:
    /// the tick is the planner, the interpolator and a refused write, not decoding.
    Soak,
}

impl Mix {
    fn program(self) -> ProgramSpec {
        match self {
            Mix::Params => ProgramSpec {
                moves: 0,
                arcs: 0,
                params: 1,
                m_functions: 0,
                ..ProgramSpec::default()
            },
            Mix::Soak => ProgramSpec::default(),
        }
    }
}

/// `n` channels built from the start-up list, each fed its own endless generated program of `mix` by
/// a client writing 992-byte packets every tick: the soak cycle without faults.
pub fn streaming_channels(
    params: &Path,
    n: u32,
    seed: u64,
    mix: Mix,
    loader: &Loader,
) -> Result<(SoakCycle, Duration), String> {
    // `ParamError` displays every diagnostic, rendered, one a line.
    let config = crate::params::load(params).map_err(|e| e.to_string())?;
    if config.channels.is_empty() {
        return Err("the start-up list has no channel".into());
    }
    let axes = crate::setup::axes(&config).map_err(|e| e.to_string())?;
    let mut rng = SplitMix64::new(seed);
    let mut channels = Vec::new();
    let mut clients = Vec::new();
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
            Source::Generated(Generator::new(mix.program(), r.fork(1))),
        );
        channels.push(crate::channel::Channel::new(
            settings,
            false,
            loader.clone(),
        ));
        clients.push((i + 1, program, feeder, r.fork(3)));
    }
    let mut machine = Machine::new(channels, EventLog::disabled(), StopWhen::Never);
    let mut slots = Vec::new();
    for (number, program, feeder, r) in clients {
        let slot = Slot::new(&mut machine, number, program, feeder, &axes, r)
            .ok_or_else(|| format!("channel {number}: not built"))?;
        slots.push(slot);
    }
    let period = Duration::from_micros(config.runtime.cycle_period_us.max(1));
    Ok((
        SoakCycle::new(machine, slots, Faults::default(), Vec::new(), None),
        period,
    ))
}

#[cfg(test)]
mod tests {
    use super::{streaming_channels, Mix};
    use crate::runtime::{Clock, Runtime};
    use crate::soak::driver::SoakCycle;
    use crate::source::loader::Loader;

    /// Two channels of `params/soak/startup4.lis` streaming `mix` for 1000 virtual ticks.
    fn run_1000_ticks(mix: Mix) -> SoakCycle {
        let params =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("params/soak/startup4.lis");
        let (cycle, period) = streaming_channels(&params, 2, 1, mix, &Loader::start()).unwrap();
        let (mut rt, _tx) = Runtime::new(cycle, period, Clock::Virtual);
        rt.run(Some(1000));
        rt.into_inner().0
    }

    /// The bench's load streams: each channel takes a packet nearly every tick, where the
    /// soak's program left the buffer standing full (a packet taken every few hundred ticks).
    #[test]
    fn the_load_takes_a_packet_nearly_every_tick() {
        let cycle = run_1000_ticks(Mix::Params);
        for c in cycle.feed_counters() {
            assert!(
                c.writes_ok >= 800,
                "{} packets taken in 1000 ticks",
                c.writes_ok
            );
        }
        assert!(
            cycle.total_blocks >= 2 * 800 * 20,
            "{} blocks",
            cycle.total_blocks
        );
    }

    /// The soak's mix stands the stream full: its moves stop at corners and its M8/M9 wait
    /// for the PLC, so a packet is taken only every so many ticks (the load the tick-work
    /// figures of earlier rounds were measured on).
    #[test]
    fn the_soak_mix_leaves_the_stream_standing_full() {
        for c in run_1000_ticks(Mix::Soak).feed_counters() {
            assert!(
                c.writes_ok < 100,
                "{} packets taken in 1000 ticks",
                c.writes_ok
            );
            assert!(c.writes_ok > 0, "the stream never started");
        }
    }
}
