//! Tick work of real channels streaming at full rate (the `ncchannel bench` load, virtual
//! time): one channel and four channels, each tick a write attempt, decode, motion and the
//! soak checks. Divide by the blocks per tick printed by `ncchannel soak` for blocks/s.

use std::path::Path;

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use ncchannel::runtime::{Cycle, Tick};
use ncchannel::soak::load::{streaming_channels, Mix};

fn soak(c: &mut Criterion) {
    let params = Path::new(env!("CARGO_MANIFEST_DIR")).join("params/soak/startup4.lis");
    for n in [1u32, 4] {
        let (mut cycle, period) =
            streaming_channels(&params, n, 1, Mix::Params, &ncchannel::Loader::start()).unwrap();
        let mut index = 0u64;
        c.bench_function(&format!("soak_tick_{n}_channels"), |b| {
            b.iter(|| {
                let tick = Tick {
                    index,
                    period,
                    time: period.saturating_mul(u32::try_from(index).unwrap_or(u32::MAX)),
                    clock: ncchannel::runtime::Clock::Virtual,
                };
                index += 1;
                black_box(cycle.step(&tick));
            })
        });
        assert_eq!(cycle.tallies.order.violations, 0);
    }
}

criterion_group!(benches, soak);
criterion_main!(benches);
