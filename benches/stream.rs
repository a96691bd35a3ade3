//! Tick work of the streaming path: one 992-byte write with CR LF validation, a segment take,
//! and a whole synthetic streaming tick (feeder + buffer + reader) as `ncchannel bench` runs it.

use std::time::Duration;

use criterion::{black_box, criterion_group, criterion_main, Criterion};

use ncchannel::report::event::EventLog;
use ncchannel::runtime::{Cycle, Tick};
use ncchannel::Feeder;
use ncchannel::StreamBuffer;

#[path = "../tests/support/streaming_load.rs"]
mod streaming_load;
use streaming_load::{generated_program, StreamingLoad};

fn stream(c: &mut Criterion) {
    let text = generated_program(200);
    let mut f = Feeder::new(text.clone(), 992, 1, false).unwrap();
    let packet = f.poll(0).unwrap().to_vec();
    let mut buf = StreamBuffer::new();
    let mut seg = Vec::with_capacity(4094);
    c.bench_function("stream_write_992_and_take", |b| {
        b.iter(|| {
            buf.write(black_box(&packet)).unwrap();
            black_box(buf.take_segment(&mut seg));
        })
    });

    let mut load = StreamingLoad::new(text, 992, 1, true, EventLog::disabled()).unwrap();
    let mut index = 0u64;
    let period = Duration::from_millis(1);
    c.bench_function("streaming_tick", |b| {
        b.iter(|| {
            let tick = Tick {
                index,
                period,
                time: Duration::from_millis(index),
                clock: ncchannel::runtime::Clock::Virtual,
            };
            index += 1;
            black_box(load.step(&tick));
        })
    });
}

criterion_group!(benches, stream);
criterion_main!(benches);
