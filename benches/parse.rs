//! Parser throughput on a 100,000-line 3-axis program, side by side with the `gcode` crate
//! parsing the same text in the same run: MB/s (`parse_bytes`) and blocks/s (`parse_blocks`).
//!
//! `cargo bench --bench parse`

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use ncchannel::lang::{parse_block, Block, Body};

const LINES: usize = 100_000;

/// `N123 G01 X12.345 Y-6.789 Z0.5 F3000` style, numbers varied by a fixed-seed LCG so every
/// run parses the same text.
fn program() -> String {
    let mut seed: u64 = 0x2545_F491_4F6C_DD1D;
    let mut next = move |m: u64| {
        seed = seed
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (seed >> 33) % m
    };
    let mut text = String::with_capacity(LINES * 40);
    for k in 0..LINES {
        let g = if next(10) == 0 { "G00" } else { "G01" };
        let x = next(400_000) as f64 / 1000.0 - 200.0;
        let y = next(400_000) as f64 / 1000.0 - 200.0;
        let z = next(20_000) as f64 / 1000.0 - 10.0;
        text.push_str(&format!("N{} {g} X{x:.3} Y{y:.3} Z{z:.3}", (k + 1) * 10));
        if next(4) == 0 {
            text.push_str(&format!(" F{}", 500 + next(5000)));
        }
        text.push_str("\r\n");
    }
    text
}

fn parse_ours(text: &str) -> Vec<Block> {
    let mut blocks = Vec::with_capacity(LINES);
    for line in text.lines() {
        match parse_block(line) {
            Ok(b) => blocks.push(b),
            Err(e) => panic!("{line}: {e}"),
        }
    }
    blocks
}

fn bench(c: &mut Criterion) {
    let text = program();
    // Both parsers must accept the whole program, or the comparison means nothing.
    assert_eq!(parse_ours(&text).len(), LINES);
    let theirs = gcode::parse(&text).expect("gcode crate parses the benchmark program");
    assert!(theirs.blocks.len() >= LINES);

    for (name, throughput) in [
        ("parse_bytes", Throughput::Bytes(text.len() as u64)),
        ("parse_blocks", Throughput::Elements(LINES as u64)),
    ] {
        let mut group = c.benchmark_group(name);
        group.sample_size(20);
        group.throughput(throughput);
        // Both build the whole program's syntax tree: the like-for-like comparison.
        group.bench_function("ncchannel", |b| b.iter(|| parse_ours(black_box(&text))));
        group.bench_function("gcode_0.7", |b| b.iter(|| gcode::parse(black_box(&text))));
        // The decoder's use: one block at a time, dropped after use.
        group.bench_function("ncchannel_line_by_line", |b| {
            b.iter(|| {
                let mut items = 0usize;
                for line in black_box(&text).lines() {
                    if let Ok(Block {
                        body: Body::Items(list),
                        ..
                    }) = parse_block(line)
                    {
                        items += list.len();
                    }
                }
                items
            })
        });
        group.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
