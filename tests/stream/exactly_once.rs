//! Exactly once under slow ticks: a stream write the runtime does not answer in time is either
//! applied (and answered OK) or answered 0x708 and never applied, so a client that retries on
//! 0x708, as every client must, never gets its lines executed twice.
//!
//! The runtime is driven into ticks far longer than the backend's reply timeout: a [`Cycle`]
//! around the real machine sleeps in every tick while the file program `slow.nc` runs (the
//! decoder bounds its own work per tick, so no NC program can make a tick long any more).

use crate::support as common;

use std::sync::Arc;
use std::time::{Duration, Instant};

use ads::{AmsAddr, AmsNetId, Client, Source, Timeouts};
use common::{of, Rig};
use ncchannel::ads::objects::offset;
use ncchannel::machine::remote::ChannelBackend;
use ncchannel::machine::{Machine, Op, Reply, Request, StopWhen};
use ncchannel::runtime::{Clock, Cycle, Flow, Runtime, Tick};
use serde_json::Value;

const CH1: u32 = 0x20101;

/// The program during whose ticks the runtime is slow: a few ticks of motion.
const SLOW_PROGRAM: &str = "N10 P2 = 0\nN20 G01 X0.01 F30000\nN30 X0\nN40 M30\n";

/// The real machine, each of whose ticks lasts `slow_tick` longer while `slow.nc` runs on
/// channel 1: the shape of a tick doing work that grows with its input.
struct SlowWhileRunning {
    machine: Machine,
    slow_tick: Duration,
}

impl Cycle for SlowWhileRunning {
    type Request = Request;

    fn serve(&mut self, req: Request, tick: &Tick) {
        self.machine.serve(req, tick);
    }

    fn step(&mut self, tick: &Tick) -> Flow {
        if let Reply::Status(s) = self.machine.apply(tick, 1, Op::Status) {
            if s.program.as_deref() == Some("slow.nc") {
                std::thread::sleep(self.slow_tick);
            }
        }
        self.machine.step(tick)
    }
}

struct Setup {
    server: ncchannel::ads::ServerHandle,
    stop: ncchannel::runtime::StopHandle,
    thread: std::thread::JoinHandle<Machine>,
    log: common::Shared2,
    client: Client,
}

/// The real channels in real time behind the ADS server; calls answer 0x708 after
/// `reply_timeout` (shorter than the shipped 500 ms where a slow tick on a fast machine
/// must still outlast it many times over).
fn setup(rig: &Rig, reply_timeout: Duration) -> Setup {
    let (mut machine, period, log) = rig.machine();
    machine.set_stop_when(StopWhen::Never);
    let cycle = SlowWhileRunning {
        machine,
        slow_tick: reply_timeout * 4,
    };
    let (mut rt, tx) = Runtime::new(cycle, period, Clock::RealTime);
    let stop = rt.stop_handle();
    let thread = std::thread::spawn(move || {
        rt.run(None);
        rt.into_inner().0.machine
    });
    let backend = ChannelBackend::new(tx, 1).with_reply_timeout(reply_timeout);
    let config = ncchannel::ads::ServerConfig {
        bind: "127.0.0.1:0".parse().unwrap(),
        ..Default::default()
    };
    let server = ncchannel::ads::spawn(config, Arc::new(backend)).unwrap();
    let client = Client::new(
        server.local_addr(),
        Timeouts::new(Duration::from_secs(60)),
        Source::Addr(AmsAddr::new(AmsNetId::new(10, 1, 2, 3, 1, 1), 40200)),
    )
    .unwrap();
    Setup {
        server,
        stop,
        thread,
        log,
        client,
    }
}

impl Setup {
    fn finish(self) -> Vec<Value> {
        drop(self.client);
        self.server.shutdown();
        self.stop.stop();
        let mut m = self.thread.join().unwrap();
        m.finish_log().unwrap();
        self.log
            .text()
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect()
    }
}

fn target() -> AmsAddr {
    AmsAddr::new(AmsNetId::new(127, 0, 0, 1, 1, 1), 553)
}

/// Read 8 bytes, retrying while the runtime is in a long tick (0x708).
fn read8(dev: &ads::Device, off: u32) -> [u8; 8] {
    let mut b = [0u8; 8];
    loop {
        match dev.read_exact(CH1, off, &mut b) {
            Ok(()) => return b,
            Err(ads::Error::Ads(_, _, 0x708)) => std::thread::sleep(Duration::from_millis(20)),
            Err(e) => panic!("read {off:#x}: {e}"),
        }
    }
}

fn state(dev: &ads::Device) -> i32 {
    let b = read8(dev, offset::MODE_STATE);
    i32::from_le_bytes(b[4..8].try_into().unwrap())
}

fn stream_used(dev: &ads::Device) -> u32 {
    let b = read8(dev, offset::STREAM_FILL);
    u32::from_le_bytes(b[0..4].try_into().unwrap())
}

/// The usual client loop: write, and on 0x708 wait a little and write again. Returns how
/// many 0x708 answers it saw.
fn write_retrying(dev: &ads::Device, packet: &[u8], deadline: Duration) -> u32 {
    let start = Instant::now();
    let mut busy = 0;
    loop {
        match dev.write(CH1, offset::STREAM, packet) {
            Ok(()) => return busy,
            Err(ads::Error::Ads(_, _, 0x708)) => {
                busy += 1;
                assert!(start.elapsed() < deadline, "still busy after {deadline:?}");
                std::thread::sleep(Duration::from_millis(20));
            }
            Err(e) => panic!("stream write: {e}"),
        }
    }
}

fn wait_state(dev: &ads::Device, want: i32, limit: Duration) {
    let start = Instant::now();
    while state(dev) != want {
        assert!(
            start.elapsed() < limit,
            "state {} never became {want}",
            state(dev)
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn start(dev: &ads::Device, program: &str) {
    dev.write_value(CH1, offset::COMMAND_MODE, &2i32).unwrap();
    dev.write(
        CH1,
        offset::COMMAND_PROGRAM,
        format!("{program}\0").as_bytes(),
    )
    .unwrap();
    dev.write_value(CH1, offset::COMMAND_STATE, &4i32).unwrap();
    // Let the runtime enter the tick that runs the program start.
    std::thread::sleep(Duration::from_millis(20));
}

/// The reproduction: a file program's first tick outlasts the reply timeout; a stream write
/// made meanwhile answers 0x708, the client retries, and the lines must still land once.
#[test]
fn a_write_answered_busy_during_a_long_tick_is_never_applied_later() {
    let rig = Rig::new();
    rig.program("slow.nc", SLOW_PROGRAM);
    let s = setup(&rig, Duration::from_millis(100));
    let dev = s.client.device(target());

    // ACTIVE starts slow.nc; its first tick then decodes the whole loop.
    start(&dev, "slow.nc");
    let packet = b"N1 P5=1\r\nN2 P6=2\r\n";
    let busy = write_retrying(&dev, packet, Duration::from_secs(300));
    assert!(
        busy > 0,
        "the write was made during the long tick and must have been answered busy at least once"
    );
    wait_state(&dev, 3, Duration::from_secs(300));
    assert_eq!(
        stream_used(&dev) as usize,
        packet.len(),
        "the stream holds the packet once"
    );

    // The streaming program executes what the stream holds.
    start(&dev, "streaming.nc");
    write_retrying(&dev, b"N3 M30\r\n", Duration::from_secs(60));
    wait_state(&dev, 3, Duration::from_secs(60));
    let events = s.finish();
    let streamed: Vec<String> = of(&events, "block")
        .iter()
        .filter(|e| e["prog"] == "streaming.nc")
        .map(|e| e["text"].as_str().unwrap().to_string())
        .collect();
    assert_eq!(streamed, ["N1 P5=1", "N2 P6=2", "N3 M30"], "each line once");
    let applied = of(&events, "write")
        .iter()
        .filter(|e| e["ok"] == true && e["bytes"] == packet.len())
        .count();
    assert_eq!(applied, 1, "the packet was applied once");
}

/// 5,000 lines through ADS while the runtime is forced into multi-second ticks every few
/// hundred lines: every block exactly once, in order.
#[test]
fn five_thousand_lines_through_multi_second_ticks_exactly_once_in_order() {
    let rig = Rig::new();
    // A second channel would be cleaner; one channel alternates: a slow file program,
    // then a stretch of the stream, and so on, the writes always overlapping slow ticks.
    rig.program("slow.nc", SLOW_PROGRAM);
    let s = setup(&rig, Duration::from_millis(50));
    let dev = s.client.device(target());
    let lines = common::streamed_5000_lines();
    let mut expected = Vec::new();
    let mut busy_total = 0;
    for chunk in lines.chunks(1000) {
        // Each chunk is its own streaming program: it sets its feed first.
        let mut chunk = chunk.to_vec();
        if !chunk[0].contains('F') {
            chunk.insert(0, "G01 F30000".to_string());
        }
        let chunk = &chunk[..];
        // Slow tick first; meanwhile a whole packet of lines is written and retried.
        start(&dev, "slow.nc");
        let mut packet = Vec::new();
        let mut held = Vec::new();
        for l in chunk.iter().take_while(|l| *l != "M30") {
            let line = format!("{l}\r\n");
            if packet.len() + line.len() > 992 {
                break;
            }
            packet.extend_from_slice(line.as_bytes());
            held.push(l.clone());
        }
        busy_total += write_retrying(&dev, &packet, Duration::from_secs(300));
        wait_state(&dev, 3, Duration::from_secs(300));
        // Then the streaming program runs the packet and the rest of the chunk.
        start(&dev, "streaming.nc");
        let rest: Vec<&String> = chunk[held.len()..].iter().filter(|l| *l != "M30").collect();
        let mut cur = Vec::new();
        for l in rest {
            let line = format!("{l}\r\n");
            if cur.len() + line.len() > 992 {
                write_retrying(&dev, &cur, Duration::from_secs(300));
                cur.clear();
            }
            cur.extend_from_slice(line.as_bytes());
        }
        if cur.len() + 5 > 992 {
            write_retrying(&dev, &cur, Duration::from_secs(300));
            cur.clear();
        }
        cur.extend_from_slice(b"M30\r\n");
        write_retrying(&dev, &cur, Duration::from_secs(300));
        expected.extend(chunk.iter().filter(|l| *l != "M30").cloned());
        expected.push("M30".to_string());
        wait_state(&dev, 3, Duration::from_secs(300));
    }
    let events = s.finish();
    let streamed: Vec<String> = of(&events, "block")
        .iter()
        .filter(|e| e["prog"] == "streaming.nc")
        .map(|e| e["text"].as_str().unwrap().to_string())
        .collect();
    assert!(busy_total > 0, "the writes overlapped slow ticks");
    assert_eq!(streamed.len(), expected.len());
    assert_eq!(streamed, expected, "every line exactly once, in order");
}

/// In ERROR nothing drains the stream until a reset deletes it: a write answers 0x707 (not
/// 0x708, which a client retries for ever) and leaves the buffer as it was.
#[test]
fn stream_writes_in_error_are_refused_not_ready() {
    let rig = Rig::new();
    let s = setup(&rig, Duration::from_secs(2));
    let dev = s.client.device(target());
    dev.write_value(CH1, offset::COMMAND_MODE, &2i32).unwrap();
    dev.write(CH1, offset::COMMAND_PROGRAM, b"missing.nc\0")
        .unwrap();
    let _ = dev.write_value(CH1, offset::COMMAND_STATE, &4i32);
    assert_eq!(
        state(&dev),
        6,
        "a missing program puts the channel in ERROR"
    );
    match dev.write(CH1, offset::STREAM, b"N1 X1\r\n") {
        Err(ads::Error::Ads(_, _, code)) => assert_eq!(code, 0x707),
        other => panic!("expected 0x707, got {other:?}"),
    }
    assert_eq!(stream_used(&dev), 0, "nothing entered the buffer");
    let events = s.finish();
    assert!(of(&events, "write").is_empty(), "no write was applied");
}

#[test]
fn stream_writes_without_a_streaming_program_are_refused_not_ready() {
    let rig = Rig::new();
    // A channel list without `streaming_prog_file`: streaming is off for this channel.
    std::fs::write(rig.dir.path().join("params/channel1.lis"), "\n").unwrap();
    let s = setup(&rig, Duration::from_secs(2));
    let dev = s.client.device(target());
    for _ in 0..3 {
        match dev.write(CH1, offset::STREAM, b"N1 X1\r\n") {
            Err(ads::Error::Ads(_, _, code)) => assert_eq!(code, 0x707),
            other => panic!("expected 0x707, got {other:?}"),
        }
    }
    assert_eq!(stream_used(&dev), 0, "nothing entered the buffer");
    let events = s.finish();
    assert!(of(&events, "write").is_empty(), "no write was applied");
}
