//! `ncchannel bench --load live-view`: what the live web view of `serve --http` costs the
//! runtime — tick work and lateness with no page connected against the same with `--pages`
//! pages reading the event stream, in alternating slices of one run, and the update rate a page
//! receives.
//!
//! The channels are those of a start-up list run as `serve` runs them, channel 1 executing a
//! generated contour (polyline chords of a circle at F6000), so the
//! page has positions, a current block and a listing to show. The pages are real HTTP
//! clients on loopback reading `GET /events` as a browser does (Server-Sent Events).

use std::io::{BufRead, BufReader, Write};
use std::net::{Shutdown, SocketAddr, TcpStream};
use std::path::Path;
use std::process::ExitCode;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::out::Stdout;
use crate::http::{ControlAccess, HttpConfig, HttpHandle};
use crate::machine::remote::ChannelBackend;
use crate::machine::{Machine, StopWhen};
use crate::report::event::EventLog;
use crate::runtime::{Clock, Runtime};
use crate::vocab::stats::CycleStats;

/// The generated program's name in its folder.
const PROGRAM: &str = "live_view_bench.nc";
/// Chord length, mm, radius, mm, and feed, mm/min, of the generated contour: 0.5 mm chords at
/// 100 mm/s are at most 200 blocks a second (fewer where the path slows at the chords' corners).
const CHORD_MM: f64 = 0.5;
const RADIUS_MM: f64 = 20.0;
const FEED_MM_PER_MIN: u32 = 6000;
/// Blocks a second the contour takes at most, and the margin of blocks over the bench's length.
const BLOCKS_PER_S: f64 = FEED_MM_PER_MIN as f64 / 60.0 / CHORD_MM;
const BLOCK_MARGIN: f64 = 2.0;
/// Ticks run after pages connect or leave before a slice is measured: the feed starts or
/// stops polling and the pages get their first updates.
const SETTLE_TICKS: u64 = 100;
/// How long the bench waits for a page to connect or to be dropped.
const PAGE_WAIT: Duration = Duration::from_secs(10);

/// Settings of one live-view bench.
pub struct LiveBench<'a> {
    pub params: &'a Path,
    pub seconds: f64,
    pub pages: usize,
}

/// One page: a loopback HTTP client reading the event stream and counting status updates.
struct Page {
    socket: TcpStream,
    reader: JoinHandle<()>,
}

impl Page {
    fn open(addr: SocketAddr, updates: Arc<AtomicU64>) -> std::io::Result<Page> {
        let mut socket = TcpStream::connect(addr)?;
        // The view answers only its own Host (DNS rebinding).
        write!(
            socket,
            "GET /events HTTP/1.1\r\nHost: {addr}\r\nAccept: text/event-stream\r\n\r\n"
        )?;
        let mut lines = BufReader::new(socket.try_clone()?);
        let reader = std::thread::spawn(move || {
            let mut line = String::new();
            while lines.read_line(&mut line).is_ok_and(|n| n > 0) {
                if line.trim_end() == "event: status" {
                    updates.fetch_add(1, Ordering::Relaxed);
                }
                line.clear();
            }
        });
        Ok(Page { socket, reader })
    }

    fn close(self) {
        let _ = self.socket.shutdown(Shutdown::Both);
        let _ = self.reader.join();
    }
}

/// Tick figures of one phase, merged over its slices.
#[derive(Default)]
struct Phase {
    stats: CycleStats,
    wall: Duration,
}

impl Phase {
    fn add(&mut self, s: &CycleStats, wall: Duration) {
        self.stats.work.merge(&s.work);
        self.stats.lateness.merge(&s.lateness);
        self.stats.overruns += s.overruns;
        self.wall += wall;
    }
}

/// The contour: `blocks` chords of a circle around (50, 50), then M30.
fn contour(blocks: u64) -> String {
    let mut text = format!(
        "N1 G90 G01 X{:.3} Y50 F{FEED_MM_PER_MIN}\n",
        50.0 + RADIUS_MM
    );
    for k in 1..=blocks {
        let a = (k as f64 * CHORD_MM / RADIUS_MM) % std::f64::consts::TAU;
        text.push_str(&format!(
            "N{} X{:.3} Y{:.3}\n",
            k + 1,
            50.0 + RADIUS_MM * a.cos(),
            50.0 + RADIUS_MM * a.sin()
        ));
    }
    text.push_str("M30\n");
    text
}

/// Run ticks until `done` holds (at most `PAGE_WAIT` of them), discarding their figures.
fn settle(rt: &mut Runtime<Machine>, done: impl Fn() -> bool) -> bool {
    let until = Instant::now() + PAGE_WAIT;
    loop {
        rt.restart_schedule();
        rt.run(Some(SETTLE_TICKS));
        rt.take_stats();
        if done() {
            return true;
        }
        if Instant::now() >= until {
            return false;
        }
    }
}

/// Runs the bench; `Err` is a usage error (the parameter lists), which `bench` reports as such.
pub fn execute(b: &LiveBench<'_>) -> Result<ExitCode, String> {
    let fail = |msg: String| {
        eprintln!("ncchannel bench: {msg}");
        ExitCode::from(super::exit::CHANNEL_ERROR)
    };
    let folder = match tempfile::tempdir() {
        Ok(d) => d,
        Err(e) => return Ok(fail(format!("a folder for the generated program: {e}"))),
    };
    let blocks = (b.seconds * 2.0 * BLOCKS_PER_S * BLOCK_MARGIN).ceil() as u64;
    if let Err(e) = std::fs::write(folder.path().join(PROGRAM), contour(blocks)) {
        return Ok(fail(format!("writing the generated program: {e}")));
    }
    let mut config = super::run::load_config(b.params)?;
    super::run::search_first(
        &mut config,
        0,
        folder.path().to_path_buf(),
        "ncchannel bench --load live-view",
    );
    let loader = crate::source::loader::Loader::start();
    let channels = match crate::setup::channels(&config, false, &loader) {
        Ok(c) => c,
        Err(e) => return Err(e.to_string()),
    };
    let nch = channels.len() as u16;
    let period = Duration::from_micros(config.runtime.cycle_period_us);
    let mut machine = Machine::new(channels, EventLog::disabled(), StopWhen::Never);
    machine.record_live();
    if let Err(e) = super::serve::start_at_first_tick(&mut machine, period, PROGRAM) {
        return Ok(fail(format!("starting the generated program: {e}")));
    }
    let (mut rt, requests) = Runtime::new(machine, period, Clock::RealTime);
    let view = HttpConfig {
        bind: SocketAddr::from(([127, 0, 0, 1], 0)),
        allow_non_loopback: false,
        controls: ControlAccess::Refused,
        allow_hosts: Vec::new(),
    };
    let backend = Arc::new(ChannelBackend::new(requests, nch));
    let web = match crate::http::spawn(&view, backend, Some(rt.live_stats())) {
        Ok(h) => h,
        Err(e) => return Ok(fail(format!("the web view: {e}"))),
    };
    let measured = alternate(&mut rt, &web, b);
    web.shutdown();
    let (without, with, updates) = match measured {
        Ok(m) => m,
        Err(e) => return Ok(fail(e)),
    };
    let executed = rt
        .cycle()
        .channels()
        .first()
        .map_or(0, |c| c.report().stats.blocks);
    Ok(report(b, period, &without, &with, updates, executed))
}

/// Slices of about a second, without and with the pages in turn, so a change of load on a
/// shared machine hits both phases alike. Returns both phases and the status updates the
/// pages received while measured.
fn alternate(
    rt: &mut Runtime<Machine>,
    web: &HttpHandle,
    b: &LiveBench<'_>,
) -> Result<(Phase, Phase, u64), String> {
    let per_second = (1.0 / rt.period().as_secs_f64()).round().max(1.0) as u64;
    let slices = (b.seconds.ceil() as u64).max(1);
    let (mut without, mut with) = (Phase::default(), Phase::default());
    let mut updates = 0;
    for _ in 0..slices {
        rt.restart_schedule();
        let s = rt.run(Some(per_second));
        without.add(&rt.take_stats(), s.wall);

        let received = Arc::new(AtomicU64::new(0));
        let mut pages = Vec::with_capacity(b.pages);
        for _ in 0..b.pages {
            let page = Page::open(web.local_addr(), Arc::clone(&received))
                .map_err(|e| format!("a page cannot connect: {e}"))?;
            pages.push(page);
        }
        if !settle(rt, || {
            web.pages_connected() == b.pages && received.load(Ordering::Relaxed) > 0
        }) {
            return Err(format!(
                "{} of {} pages connected and receiving after {PAGE_WAIT:?}",
                web.pages_connected(),
                b.pages
            ));
        }
        let before = received.load(Ordering::Relaxed);
        rt.restart_schedule();
        let s = rt.run(Some(per_second));
        with.add(&rt.take_stats(), s.wall);
        updates += received.load(Ordering::Relaxed) - before;

        for p in pages {
            p.close();
        }
        if !settle(rt, || web.pages_connected() == 0) {
            return Err(format!(
                "{} pages still connected {PAGE_WAIT:?} after they closed",
                web.pages_connected()
            ));
        }
    }
    Ok((without, with, updates))
}

fn report(
    b: &LiveBench<'_>,
    period: Duration,
    without: &Phase,
    with: &Phase,
    updates: u64,
    executed: u64,
) -> ExitCode {
    let mut out = Stdout::new();
    out.line(format_args!(
        "bench: {} in real time at {} µs, channel 1 running a contour of {CHORD_MM} mm chords at F{FEED_MM_PER_MIN}; {:.2} s without a page and {:.2} s with {} page(s) on the event stream, alternating",
        b.params.display(),
        period.as_micros(),
        without.wall.as_secs_f64(),
        with.wall.as_secs_f64(),
        b.pages
    ));
    out.line("all figures in µs");
    for (name, p) in [("no page", without), ("pages connected", with)] {
        out.line(format_args!(
            "{name:<16} tick work p50 {:>7.2} p99 {:>7.2} p99.9 {:>8.2} max {:>8.2}; lateness p99 {:>8.2}; overruns {} (n = {})",
            p.stats.work.quantile_us(0.5),
            p.stats.work.quantile_us(0.99),
            p.stats.work.quantile_us(0.999),
            p.stats.work.max_us(),
            p.stats.lateness.quantile_us(0.99),
            p.stats.overruns,
            p.stats.work.count()
        ));
    }
    let secs = with.wall.as_secs_f64().max(1e-9);
    out.line(format_args!(
        "updates received: {updates} status events over {} page(s) in {secs:.2} s = {:.1} per second per page (the feed's period is {} ms)",
        b.pages,
        updates as f64 / secs / b.pages.max(1) as f64,
        crate::http::FEED_PERIOD.as_millis()
    ));
    out.line(format_args!(
        "ratio tick work p50 with / without pages: {:.2}; p99: {:.2}; channel 1 executed {executed} blocks",
        with.stats.work.quantile_us(0.5) / without.stats.work.quantile_us(0.5).max(1e-9),
        with.stats.work.quantile_us(0.99) / without.stats.work.quantile_us(0.99).max(1e-9)
    ));
    out.finish_or_say("ncchannel bench");
    ExitCode::from(super::exit::OK)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_contour_is_a_closed_circle_of_chords() {
        let text = contour(400);
        assert_eq!(text.lines().count(), 402);
        assert!(text.ends_with("M30\n"));
        // 400 chords of 0.5 mm: 200 mm, 1.6 turns of a 125.7 mm circle; every point on it.
        for l in text.lines().skip(1).take(400) {
            let v: Vec<f64> = l
                .split_whitespace()
                .skip(1)
                .map(|w| w[1..].parse().unwrap())
                .collect();
            let r = ((v[0] - 50.0).powi(2) + (v[1] - 50.0).powi(2)).sqrt();
            assert!((r - RADIUS_MM).abs() < 1e-3, "{l}");
        }
    }
}
