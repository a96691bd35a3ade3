//! A channel-shaped synthetic load for the stream benchmark and the runtime tests: a feeder
//! writing into a stream buffer and a reader taking segments out, with the events a channel
//! would log. Shared by `tests/` and `benches/stream.rs` (`#[path]`), kept out of the library.

#![allow(dead_code)]

use crossbeam_channel::Sender;

use ncchannel::report::event::{EventBuffer, EventKind, EventLog};
use ncchannel::runtime::{Cycle, Flow, Tick};
use ncchannel::{Feeder, FeederError};
use ncchannel::{StreamBuffer, StreamWriteError, MAX_PROGRAM_STREAM_SIZE};

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
