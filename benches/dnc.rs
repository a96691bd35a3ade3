//! Splitting throughput of the DNC receiver on a 100 MB transfer (target ≥ 200 MB/s).
//!
//! The splitter alone, fed 64 KiB chunks like the reader does, into a sink that only counts:
//! this measures the state machine, not the disk.

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use ncchannel::dnc::{Anchor, Markers, ProgramEnd, ProgramSink, ProgramStart, Splitter};

const SIZE: usize = 100 * 1024 * 1024;

/// A SINUMERIK-style archive: programs of 2000 blocks with name lines and workpiece paths,
/// some noise between them, CR LF line ends.
fn transfer() -> Vec<u8> {
    let mut out = Vec::with_capacity(SIZE + 4096);
    let mut p = 0u32;
    while out.len() < SIZE {
        out.extend_from_slice(format!("%_N_PART{p}_MPF\r\n").as_bytes());
        out.extend_from_slice(format!(";$PATH=/_N_WKS_DIR/_N_WP{}_WPD\r\n", p % 7).as_bytes());
        for n in 1..2000u32 {
            let line = format!(
                "N{} G1 X{}.{:03} Y{}.{:03} Z-1.5 F{} ; cut\r\n",
                n * 10,
                n % 400,
                (n * 37) % 1000,
                (n * 7) % 300,
                (n * 11) % 1000,
                800 + n % 5 * 100
            );
            out.extend_from_slice(line.as_bytes());
        }
        out.extend_from_slice(b"N99999 M30\r\n\r\n");
        p += 1;
    }
    out
}

#[derive(Default)]
struct Count {
    programs: usize,
    bytes: u64,
}

impl ProgramSink for Count {
    type Error = std::convert::Infallible;
    fn start(&mut self, _: &ProgramStart) -> Result<(), Self::Error> {
        self.programs += 1;
        Ok(())
    }
    fn data(&mut self, b: &[u8]) -> Result<(), Self::Error> {
        self.bytes += b.len() as u64;
        Ok(())
    }
    fn end(&mut self, e: ProgramEnd) -> Result<(), Self::Error> {
        black_box(e);
        Ok(())
    }
}

fn split(m: &Markers, data: &[u8]) -> Count {
    let mut s = Splitter::new(m.clone());
    let mut c = Count::default();
    for chunk in data.chunks(64 * 1024) {
        let Ok(()) = s.feed(chunk, &mut c);
    }
    let Ok(_) = s.finish(&mut c);
    c
}

fn bench(c: &mut Criterion) {
    let data = transfer();
    let none: [&str; 0] = [];
    let cases = [
        (
            "start_end",
            Markers::new(["%"], ["M30", "M17", "M02"], Anchor::Anywhere).unwrap(),
        ),
        (
            "start_only",
            Markers::new(["%"], none, Anchor::Anywhere).unwrap(),
        ),
        (
            "end_only",
            Markers::new(none, ["M30", "M02"], Anchor::Anywhere).unwrap(),
        ),
        (
            "start_end_line_start",
            Markers::new(["%"], ["N99999 M30"], Anchor::LineStart).unwrap(),
        ),
    ];
    let mut g = c.benchmark_group("dnc_split_100MB");
    g.throughput(Throughput::Bytes(data.len() as u64));
    g.sample_size(10);
    for (name, m) in &cases {
        let c = split(m, &data);
        assert!(c.programs > 100, "{name}: {} programs", c.programs);
        g.bench_function(*name, |b| b.iter(|| split(m, black_box(&data))));
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
