//! `ncchannel bench --load ads-stream`: the data-streaming interface's throughput over a real
//! ADS/TCP connection — the channels of a start-up list behind the ADS server as `serve` runs
//! them, and one sequential client streaming 17-byte lines as fast as the channel takes them.
//!
//! The figure is bytes accepted per second against the interface's nominal rate: one full
//! 4094-byte buffer per cycle (ISG FCT-C19 Data streaming: `MAX_PROGRAM_STREAM_SIZE`), that
//! is 4.094 MB/s at 1 ms. The client is sequential, one write in flight, as pyads, AdsLib and
//! ads-client stream: whole lines in packets of at most 992 bytes, retried after `--retry-us`
//! while the channel answers 0x708 (buffer full, warning 11012).

use std::net::SocketAddr;
use std::path::Path;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::{Duration, Instant};

use super::out::{say, Stdout};
use crate::ads::client::{self, AdsClient, ClientError};
use crate::ads::frame::AmsAddr;
use crate::ads::objects::{offset, GROUP_CHANNEL, PORT_CNC_COM};
use crate::ads::result::AdsResult;
use crate::ads::ServerConfig;
use crate::machine::remote::ChannelBackend;
use crate::machine::{Machine, StopWhen};
use crate::report::event::EventLog;
use crate::runtime::{Clock, Runtime};
use crate::source::stream::{MAX_PROGRAM_STREAM_INPUT_SIZE, MAX_PROGRAM_STREAM_SIZE};
use crate::vocab::stats::Histogram;

/// Bytes of every streamed line, CR LF included: the short lines the clients and a
/// CAM system's fine polylines send.
pub(crate) const LINE_BYTES: usize = 17;

/// Time streamed before the measurement starts (connection set up, program started, buffers
/// filled), so the figure is the steady rate.
const WARMUP: Duration = Duration::from_millis(500);

/// What the 17-byte lines do.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum LineKind {
    /// `N12345 P1=12345`: parameter assignments, which take no motion time: the interface's
    /// and the decoder's rate alone.
    Params,
    /// `X52.345 Y47.655`: a CAM polyline of 0.05 mm G01 steps on a circle at F30000: motion
    /// bounds the rate (each block takes its travel time).
    Moves,
}

/// Line `k` (0-based) of the endless program of `kind`; always [`LINE_BYTES`] long.
pub(crate) fn line(kind: LineKind, k: u64) -> String {
    match kind {
        LineKind::Params => {
            let n = 10_000 + k % 90_000;
            format!("N{n} P1={n}\r\n")
        }
        LineKind::Moves => {
            // 0.05 mm chords of a circle of radius 20 mm around (50, 50): both coordinates
            // stay within 30…70, so every line has the same width.
            const RADIUS_MM: f64 = 20.0;
            const STEP_MM: f64 = 0.05;
            let a = (k as f64 * STEP_MM / RADIUS_MM) % std::f64::consts::TAU;
            format!(
                "X{:06.3} Y{:06.3}\r\n",
                50.0 + RADIUS_MM * a.cos(),
                50.0 + RADIUS_MM * a.sin()
            )
        }
    }
}

/// The first lines of a `kind` stream: a move needs its feed once (not counted in the figure).
fn preamble(kind: LineKind) -> &'static [u8] {
    match kind {
        LineKind::Params => b"",
        LineKind::Moves => b"G01 X70 Y50 F30000\r\n",
    }
}

/// What the client measured.
#[derive(Debug, Default)]
struct Measured {
    bytes: u64,
    writes: u64,
    busy: u64,
    elapsed: Duration,
    rtt: Histogram,
}

/// Settings of one ADS streaming bench.
pub struct AdsBench<'a> {
    pub params: &'a Path,
    pub seconds: f64,
    pub lines: LineKind,
    pub retry: Duration,
}

pub fn execute(b: &AdsBench<'_>) -> ExitCode {
    let usage = |msg: String| {
        eprintln!("ncchannel bench: {msg}");
        ExitCode::from(super::exit::USAGE)
    };
    let loader = crate::source::loader::Loader::start();
    let (config, channels) = match super::run::load_channels(b.params, false, &loader) {
        Ok(c) => c,
        Err(e) => return usage(e),
    };
    let Some(program) = config
        .channels
        .first()
        .and_then(|c| c.streaming_prog_file.clone())
    else {
        return usage(format!(
            "{}: channel 1 has no streaming program",
            b.params.display()
        ));
    };
    let nch = channels.len() as u16;
    let period = Duration::from_micros(config.runtime.cycle_period_us);
    let machine = Machine::new(channels, EventLog::disabled(), StopWhen::Never);
    let (mut rt, requests) = Runtime::new(machine, period, Clock::RealTime);
    let net_id = config.runtime.ads.net_id;
    let server_config = ServerConfig {
        bind: SocketAddr::from(([127, 0, 0, 1], 0)),
        net_id: Some(net_id),
        ..ServerConfig::default()
    };
    let backend =
        ChannelBackend::new(requests, nch).with_reply_timeout(config.runtime.ads.reply_timeout());
    let server = match crate::ads::spawn(server_config, Arc::new(backend)) {
        Ok(s) => s,
        Err(e) => return usage(format!("cannot listen: {e}")),
    };
    let addr = server.local_addr();
    let stop = rt.stop_handle();
    let ticking = std::thread::spawn(move || {
        rt.run(None);
        rt
    });
    let target = AmsAddr {
        net_id,
        port: PORT_CNC_COM,
    };
    let measured = stream(addr, target, &program, b);
    stop.stop();
    let rt = ticking.join();
    server.shutdown();
    let measured = match measured {
        Ok(m) => m,
        Err(e) => {
            eprintln!("ncchannel bench: client: {e}");
            return ExitCode::from(super::exit::CHANNEL_ERROR);
        }
    };
    let Ok(rt) = rt else {
        eprintln!("ncchannel bench: the runtime thread panicked");
        return ExitCode::from(super::exit::CHANNEL_ERROR);
    };
    let ticks = rt.ticks();
    let (machine, stats) = rt.into_inner();
    let blocks = machine
        .channels()
        .first()
        .map_or(0, |c| c.report().stats.blocks);
    let code = report(b, period, &measured);
    // The cycle under this load: on a shared machine a starved runtime shows here.
    say(format_args!(
        "runtime: {ticks} ticks, channel 1 executed {blocks} blocks (warm-up included); {}",
        stats.describe()
    ));
    code
}

/// Connect, start the streaming program, stream for the warm-up and then `b.seconds`.
fn stream(
    addr: SocketAddr,
    target: AmsAddr,
    program: &str,
    b: &AdsBench<'_>,
) -> Result<Measured, ClientError> {
    let mut c = AdsClient::connect(addr, target, None, Duration::from_secs(5))?;
    client::start_program(&mut c, 1, program)?;
    let group = GROUP_CHANNEL + 1;
    let mut k = 0u64;
    let mut packet = Vec::with_capacity(MAX_PROGRAM_STREAM_INPUT_SIZE);
    packet.extend_from_slice(preamble(b.lines));
    let mut m = Measured::default();
    let start = Instant::now();
    let mut measuring: Option<Instant> = None;
    let length = Duration::from_secs_f64(b.seconds);
    loop {
        while packet.len() + LINE_BYTES <= MAX_PROGRAM_STREAM_INPUT_SIZE {
            packet.extend_from_slice(line(b.lines, k).as_bytes());
            k += 1;
        }
        let sent = Instant::now();
        let r = c.write(group, offset::STREAM, &packet);
        let now = Instant::now();
        if measuring.is_none() && now - start >= WARMUP {
            measuring = Some(now);
        }
        if measuring.is_some() {
            m.rtt.record(now - sent);
        }
        match r {
            Ok(()) => {
                if measuring.is_some() {
                    m.bytes += packet.len() as u64;
                    m.writes += 1;
                }
                packet.clear();
            }
            Err(ClientError::Ads(AdsResult::BUSY)) => {
                if measuring.is_some() {
                    m.busy += 1;
                }
                spin_sleep::sleep(b.retry);
            }
            Err(e) => return Err(e),
        }
        if let Some(t0) = measuring {
            m.elapsed = now - t0;
            if m.elapsed >= length {
                return Ok(m);
            }
        }
    }
}

fn report(b: &AdsBench<'_>, period: Duration, m: &Measured) -> ExitCode {
    let secs = m.elapsed.as_secs_f64().max(1e-9);
    let rate = m.bytes as f64 / secs;
    let nominal = MAX_PROGRAM_STREAM_SIZE as f64 / period.as_secs_f64();
    let mut out = Stdout::new();
    out.line(format_args!(
        "bench: {} over ADS/TCP, {} {LINE_BYTES}-byte lines ({:?}), one sequential client, {secs:.2} s after {} ms warm-up",
        b.params.display(),
        match b.lines {
            LineKind::Params => "parameter",
            LineKind::Moves => "G01",
        },
        line(b.lines, 0).trim_end(),
        WARMUP.as_millis()
    ));
    out.line(format_args!(
        "accepted {:.3} MB/s = {:.1} % of the interface's {:.3} MB/s ({MAX_PROGRAM_STREAM_SIZE} bytes per {} µs cycle); {:.0} lines/s",
        rate / 1e6,
        100.0 * rate / nominal,
        nominal / 1e6,
        period.as_micros(),
        rate / LINE_BYTES as f64
    ));
    out.line(format_args!(
        "{} writes accepted, {} answered busy (0x708, retried after {} µs); write round trip µs p50 {:.0} p99 {:.0} max {:.0}",
        m.writes,
        m.busy,
        b.retry.as_micros(),
        m.rtt.quantile_us(0.5),
        m.rtt.quantile_us(0.99),
        m.rtt.max_us()
    ));
    out.finish_or_say("ncchannel bench");
    ExitCode::from(super::exit::OK)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_line_is_17_bytes_of_one_nc_line() {
        for kind in [LineKind::Params, LineKind::Moves] {
            for k in (0..200_000).step_by(997) {
                let l = line(kind, k);
                assert_eq!(l.len(), LINE_BYTES, "{l:?}");
                assert!(l.ends_with("\r\n") && !l[..15].contains('\n'), "{l:?}");
            }
        }
    }
}
