//! The shipped settings take the stream interface's full rate: a client that keeps the
//! 4094-byte buffer full of 17-byte lines gets ≥ 90 % of a buffer a cycle through, every line
//! executed once and in order (virtual time: a property of the settings, not a timing; the
//! rate over real ADS is `ncchannel bench --load ads-stream`).

use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use ncchannel::channel::State;
use ncchannel::machine::{Op, Reply};
use ncchannel::runtime::Tick;

const LINE_BYTES: usize = 17;
const BUFFER_BYTES: u64 = 4094;

/// The N number of line `i`: five digits, so every line is 17 bytes.
fn number(i: u64) -> u32 {
    10_000 + (i % 90_000) as u32
}

/// 58 lines `N12345 P1=12345` (986 bytes), lines `k`….
fn packet(k: u64) -> Vec<u8> {
    (k..k + 58)
        .flat_map(|i| format!("N{0} P1={0}\r\n", number(i)).into_bytes())
        .collect()
}

/// Lines accepted per tick, and the executed blocks, over `ticks` ticks of a client that
/// writes until the channel answers busy.
fn stream_for(startup: &Path, ticks: u64) -> (u64, Vec<Option<u32>>) {
    let config = ncchannel::params::load(startup).unwrap();
    let mut ch = ncchannel::channels(&config, false, &ncchannel::Loader::start())
        .unwrap()
        .remove(0);
    let period = Duration::from_micros(config.runtime.cycle_period_us);
    let tick = |index: u64| Tick {
        index,
        period,
        time: period * index as u32,
        clock: ncchannel::runtime::Clock::Virtual,
    };
    assert_eq!(
        ch.apply(&tick(0), Op::Start("streaming.nc".into())),
        Reply::Command(Ok(()))
    );
    ch.apply(&tick(0), Op::ObserveStreamBlocks(true));
    let (mut next, mut accepted, mut executed) = (0u64, 0u64, Vec::new());
    let mut pending = packet(next);
    for t in 1..=ticks {
        while ch.apply(&tick(t), Op::WriteStream(Arc::from(pending.as_slice())))
            == Reply::Stream(Ok(()))
        {
            accepted += pending.len() as u64;
            next += 58;
            pending = packet(next);
        }
        ch.step(&tick(t));
        assert_eq!(ch.status().state, State::Active);
        if let Reply::Executed(e) = ch.apply(&tick(t), Op::DrainExecuted) {
            executed.extend(e.into_iter().map(|b| b.n));
        }
    }
    (accepted, executed)
}

#[test]
fn shipped_settings_take_a_full_buffer_of_17_byte_lines_every_cycle() {
    let startup = Path::new(env!("CARGO_MANIFEST_DIR")).join("params/startup.lis");
    let ticks = 2_000;
    let (accepted, executed) = stream_for(&startup, ticks);
    let per_tick = accepted as f64 / ticks as f64;
    assert!(
        per_tick >= 0.9 * BUFFER_BYTES as f64,
        "{per_tick:.0} bytes a tick accepted, want ≥ 90 % of {BUFFER_BYTES}"
    );
    // Every executed line is the next one, and all but the last buffer's worth ran.
    for (i, n) in executed.iter().enumerate() {
        assert_eq!(*n, Some(number(i as u64)), "block {i}");
    }
    let lines = accepted / LINE_BYTES as u64;
    assert!(executed.len() as u64 + 2 * BUFFER_BYTES / LINE_BYTES as u64 >= lines);
}
