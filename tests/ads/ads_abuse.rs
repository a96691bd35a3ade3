//! ADS abuse against a real `ncchannel serve` over loopback: too many connections, a client
//! that never reads, a slow client, malformed frames, random bytes, a notification flood and
//! idle connections. After each abuse a normal client must be served at once, the server's
//! resident set must stay within a bound, and the channel's tick counter (`cnc_tick_counter_r`,
//! group 0x120101 offset 0x251, docs/ads.md) must advance at the period. Each test prints its
//! figures (`ABUSE …` lines; `cargo test --test ads ads_abuse -- --nocapture` shows them). The
//! limits are explained in docs/ads-limits.md.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::Path;
use std::process::{Child, ChildStdout, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use ncchannel::ads::frame::{self, AmsAddr, AmsHeader, CommandId, Frame};
use ncchannel::vocab::ams::AmsNetId;

use crate::support as common;
use crate::support::abuse as abuse_common;
use crate::support::ads as ads_common;

use ads_common::{read_req, u32_at};

/// How much the server's resident set may grow over one abuse.
const RSS_GROWTH_BOUND_KIB: u64 = 64 * 1024;
/// A normal client's request is answered within this (generous on a loaded 2-core machine).
const SERVED_WITHIN: Duration = Duration::from_secs(3);
const TICK_GROUP: u32 = 0x120101;
const TICK_OFFSET: u32 = 0x251;

/// One spawned `serve` at a time: each test checks the cycle's pace under its abuse, which
/// two abuses at once on a 2-core machine would measure together.
static ONE_SERVE_AT_A_TIME: Mutex<()> = Mutex::new(());

pub(crate) type Turn = std::sync::MutexGuard<'static, ()>;

/// Wait for the turn to spawn a `serve`.
pub(crate) fn turn() -> Turn {
    ONE_SERVE_AT_A_TIME
        .lock()
        .unwrap_or_else(|p| p.into_inner())
}

/// A spawned `ncchannel serve`, its address, NetId and collected standard error.
pub(crate) struct Serve {
    _turn: Turn,
    pub(crate) child: Child,
    addr: SocketAddr,
    net_id: AmsNetId,
    /// The route service's UDP address, from the listening line.
    route_service: Option<SocketAddr>,
    period: Duration,
    pub(crate) stderr: Arc<Mutex<String>>,
    /// Held and never read (`--events -` into a pipe nobody reads).
    _stdout: Option<ChildStdout>,
}

impl Serve {
    pub(crate) fn start(extra: &[&str]) -> Serve {
        Self::start_with(Path::new("params/startup.lis"), extra)
    }

    fn start_with(params: &Path, extra: &[&str]) -> Serve {
        let turn = turn();
        let mut child = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .args(["serve", "--bind", "127.0.0.1:0", "--params"])
            .arg(params)
            .args(extra)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("ncchannel serve starts");
        let (first, stderr) = abuse_common::collect(child.stderr.take().expect("stderr"));
        Self::from_child(turn, child, &first, stderr)
    }

    /// A started `serve` whose first stderr line was `first` (its stdout, if piped, is held
    /// and never read); `stderr` is what the test collects of the rest.
    pub(crate) fn from_child(
        turn: Turn,
        mut child: Child,
        first: &str,
        stderr: Arc<Mutex<String>>,
    ) -> Serve {
        let stdout = child.stdout.take();
        // "<time> listening on 127.0.0.1:PORT (AMS NetId a.b.c.d.e.f, port 553, N channel(s), cycle P µs)"
        let words: Vec<&str> = abuse_common::unstamped(first).split_whitespace().collect();
        assert_eq!(words.get(..2), Some(&["listening", "on"][..]), "{first}");
        let addr: SocketAddr = words[2].parse().expect("address");
        let net_id: AmsNetId = words[5].trim_end_matches(',').parse().expect("NetId");
        let cycle = words
            .iter()
            .position(|w| *w == "cycle")
            .and_then(|i| words[i + 1].parse::<u64>().ok())
            .expect("cycle");
        let route_service = words
            .iter()
            .position(|w| *w == "UDP")
            .and_then(|i| words[i + 1].trim_end_matches(',').parse().ok());
        Serve {
            _turn: turn,
            child,
            addr,
            net_id,
            route_service,
            period: Duration::from_micros(cycle),
            stderr,
            _stdout: stdout,
        }
    }

    pub(crate) fn rss_kib(&self) -> u64 {
        abuse_common::rss_kib(self.child.id())
    }

    pub(crate) fn log(&self) -> String {
        self.stderr.lock().unwrap().clone()
    }

    /// The log once it says `needle`, or as it is after 30 s if it never does (the reading
    /// thread appends a line a moment after the server writes it).
    pub(crate) fn log_once_it_says(&self, needle: &str) -> String {
        abuse_common::log_once_it_holds(&self.stderr, needle, 1, Duration::from_secs(30))
    }

    pub(crate) fn addr(&self) -> SocketAddr {
        self.addr
    }

    pub(crate) fn route_service(&self) -> SocketAddr {
        self.route_service
            .expect("the listening line names the route service")
    }

    pub(crate) fn device(&self) -> AmsAddr {
        AmsAddr {
            net_id: self.net_id,
            port: 553,
        }
    }

    pub(crate) fn connect(&self) -> Conn {
        Conn::new(
            TcpStream::connect(self.addr).expect("connect"),
            self.device(),
        )
    }

    /// A normal client reads the tick counter now and one second later: it must be served at
    /// once and the counter must have advanced at the period. Prints and checks the figures.
    pub(crate) fn check_healthy(&self, abuse: &str, rss_before: u64) {
        let mut c = self.connect();
        let asked = Instant::now();
        let t0 = c
            .read_tick()
            .unwrap_or_else(|| panic!("{abuse}: normal client not served"));
        let answer = asked.elapsed();
        assert!(answer < SERVED_WITHIN, "{abuse}: answered after {answer:?}");
        let since = Instant::now();
        std::thread::sleep(Duration::from_secs(1));
        let t1 = c.read_tick().expect("second tick read");
        let wall = since.elapsed();
        let advanced = u64::from(t1.wrapping_sub(t0));
        let expected = wall.as_secs_f64() / self.period.as_secs_f64();
        let rss_after = self.rss_kib();
        println!(
            "ABUSE {abuse}: RSS before {rss_before} KiB, after {rss_after} KiB; normal client answered in {:.1} ms; tick counter +{advanced} in {:.3} s (period {} µs: {:.0} expected, {:.1} %)",
            answer.as_secs_f64() * 1e3,
            wall.as_secs_f64(),
            self.period.as_micros(),
            expected,
            100.0 * advanced as f64 / expected
        );
        assert!(
            advanced as f64 >= 0.5 * expected,
            "{abuse}: the cycle fell behind: {advanced} ticks in {wall:?}"
        );
        assert!(
            rss_after <= rss_before + RSS_GROWTH_BOUND_KIB,
            "{abuse}: resident set grew from {rss_before} to {rss_after} KiB"
        );
    }
}

impl Drop for Serve {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A frame-level client connection.
pub(crate) struct Conn {
    pub(crate) stream: TcpStream,
    device: AmsAddr,
    buf: Vec<u8>,
    invoke: u32,
}

fn client_addr() -> AmsAddr {
    AmsAddr {
        net_id: "127.0.0.1.1.1".parse().expect("NetId"),
        port: 40001,
    }
}

pub(crate) fn request(device: AmsAddr, command: CommandId, invoke: u32, data: &[u8]) -> Vec<u8> {
    frame::encode(
        &AmsHeader {
            target: device,
            source: client_addr(),
            command,
            state_flags: frame::FLAGS_REQUEST,
            error: 0,
            invoke_id: invoke,
        },
        data,
    )
}

/// A Read of the tick counter.
fn tick_request(device: AmsAddr, invoke: u32) -> Vec<u8> {
    request(
        device,
        CommandId::Read,
        invoke,
        &read_req(TICK_GROUP, TICK_OFFSET, 4),
    )
}

/// AddDeviceNotification of the tick counter: cyclic (mode 3), no max delay, `cycle_100ns`.
pub(crate) fn add_notification_payload(cycle_100ns: u32) -> Vec<u8> {
    let mut add = read_req(TICK_GROUP, TICK_OFFSET, 4);
    for v in [3u32, 0, cycle_100ns] {
        add.extend_from_slice(&v.to_le_bytes());
    }
    add.extend_from_slice(&[0; 16]);
    add
}

impl Conn {
    fn new(stream: TcpStream, device: AmsAddr) -> Conn {
        stream.set_nodelay(true).expect("nodelay");
        Conn {
            stream,
            device,
            buf: Vec::new(),
            invoke: 0,
        }
    }

    pub(crate) fn send(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.stream.write_all(bytes)
    }

    /// The next response frame (notifications skipped) within [`SERVED_WITHIN`].
    fn response(&mut self) -> Option<(AmsHeader, Vec<u8>)> {
        let deadline = Instant::now() + SERVED_WITHIN;
        loop {
            while let Ok(Some((f, n))) = frame::decode(&self.buf, 1 << 20) {
                self.buf.drain(..n);
                if let Frame::Ams { header, data } = f {
                    if header.command != CommandId::DeviceNotification {
                        return Some((header, data));
                    }
                }
            }
            let left = deadline.checked_duration_since(Instant::now())?;
            self.stream
                .set_read_timeout(Some(left.max(Duration::from_millis(1))))
                .ok()?;
            let mut chunk = [0u8; 8192];
            match self.stream.read(&mut chunk) {
                Ok(0) | Err(_) => return None,
                Ok(n) => self.buf.extend_from_slice(&chunk[..n]),
            }
        }
    }

    pub(crate) fn call(&mut self, command: CommandId, data: &[u8]) -> Option<Vec<u8>> {
        self.invoke += 1;
        let bytes = request(self.device, command, self.invoke, data);
        self.send(&bytes).ok()?;
        self.response().map(|(_, d)| d)
    }

    pub(crate) fn read_tick(&mut self) -> Option<u32> {
        let d = self.call(CommandId::Read, &read_req(TICK_GROUP, TICK_OFFSET, 4))?;
        (d.len() >= 12 && u32_at(&d, 0) == 0).then(|| u32_at(&d, 8))
    }

    /// True when the server closed the connection within `timeout`.
    pub(crate) fn closed_within(&mut self, timeout: Duration) -> bool {
        ads_common::closed_within(&mut self.stream, timeout)
    }
}

/// Wait until the server answers a normal client again (a refused connection is closed at
/// once; the slots of closed connections free within a moment).
fn served_again(srv: &Serve, within: Duration) -> bool {
    let until = Instant::now() + within;
    while Instant::now() < until {
        if srv.connect().read_tick().is_some() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    false
}

#[test]
fn connections_beyond_the_limit_are_refused_and_the_served_ones_are_undisturbed() {
    let srv = Serve::start(&[]);
    let rss = srv.rss_kib();
    let limit = ncchannel::vocab::ams::DEFAULT_MAX_CONNECTIONS;
    let mut held: Vec<Conn> = (0..limit).map(|_| srv.connect()).collect();
    for (i, c) in held.iter_mut().enumerate() {
        assert!(
            c.read_tick().is_some(),
            "connection {i} within the limit served"
        );
    }
    for i in 0..8 {
        let mut extra = srv.connect();
        assert!(
            extra.closed_within(Duration::from_secs(5)),
            "connection {} beyond the limit {limit} closed at once",
            limit + i
        );
    }
    for (i, c) in held.iter_mut().enumerate() {
        assert!(c.read_tick().is_some(), "held connection {i} still served");
    }
    drop(held);
    assert!(served_again(&srv, Duration::from_secs(30)));
    let log = srv.log_once_it_says("connection limit 64 reached");
    assert!(log.contains("connection limit 64 reached"), "{log}");
    srv.check_healthy("64 connections + 8 beyond the limit", rss);
}

#[test]
fn a_client_that_never_reads_is_dropped_with_bounded_memory() {
    let srv = Serve::start(&[]);
    let rss = srv.rss_kib();
    let mut c = srv.connect();
    c.stream
        .set_write_timeout(Some(Duration::from_secs(1)))
        .expect("timeout");
    // Pipelined ReadDeviceInfo requests, never a response read: 1000 frames per write.
    let one = request(srv.device(), CommandId::ReadDeviceInfo, 1, &[]);
    let batch: Vec<u8> = one.iter().copied().cycle().take(one.len() * 1000).collect();
    let started = Instant::now();
    let mut sent = 0usize;
    while started.elapsed() < Duration::from_secs(60) {
        if c.send(&batch).is_err() {
            break;
        }
        sent += 1000;
        if srv.log().contains("does not read") {
            break;
        }
    }
    let until = Instant::now() + Duration::from_secs(20);
    while !srv.log().contains("does not read") && Instant::now() < until {
        std::thread::sleep(Duration::from_millis(100));
    }
    let log = srv.log();
    assert!(
        log.contains("the client does not read; connection dropped"),
        "after {sent} requests: {log}"
    );
    println!(
        "ABUSE never-reading client: {sent} requests sent unread, dropped after {:.1} s",
        started.elapsed().as_secs_f64()
    );
    drop(c);
    srv.check_healthy("a client that never reads", rss);
}

#[test]
fn a_client_sending_one_byte_a_second_is_served_and_holds_no_one_up() {
    let srv = Serve::start(&[]);
    let rss = srv.rss_kib();
    let bytes = tick_request(srv.device(), 7);
    let mut slow = srv.connect();
    for (i, b) in bytes.iter().enumerate() {
        slow.send(&[*b]).expect("slow byte");
        if i % 10 == 0 {
            // Meanwhile everybody else is served at once.
            assert!(
                srv.connect().read_tick().is_some(),
                "served while the slow client sends"
            );
        }
        std::thread::sleep(Duration::from_secs(1));
    }
    let (header, data) = slow.response().expect("the slow client is answered");
    assert_eq!(header.invoke_id, 7);
    assert_eq!(u32_at(&data, 0), 0);
    println!(
        "ABUSE slow client: {} bytes at one a second, answered",
        bytes.len()
    );
    srv.check_healthy("a client sending one byte a second", rss);
}

#[test]
fn malformed_frames_close_their_connection_only() {
    let srv = Serve::start(&[]);
    let rss = srv.rss_kib();
    let good = tick_request(srv.device(), 1);
    let mut inconsistent = good.clone();
    inconsistent[6 + 20] = 99; // AMS data length 99, AMS/TCP length says 12
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("length 0", vec![0, 0, 0, 0, 0, 0]),
        (
            "length 31",
            [&[0u8, 0, 31, 0, 0, 0][..], &[0u8; 31]].concat(),
        ),
        ("length u32::MAX", vec![0, 0, 0xFF, 0xFF, 0xFF, 0xFF]),
        ("length 1 GiB", vec![0, 0, 0, 0, 0, 0x40]),
        ("AMS data length inconsistent", inconsistent),
    ];
    for (what, bytes) in &cases {
        let mut c = srv.connect();
        c.send(bytes).expect("send");
        assert!(c.closed_within(Duration::from_secs(5)), "{what}: closed");
        assert!(srv.connect().read_tick().is_some(), "{what}: others served");
    }
    // A flood of 6-byte router frames with an unknown command: answered by nothing, and
    // logged at most once a second.
    let mut c = srv.connect();
    let flood: Vec<u8> = [0x99u8, 0x99, 0, 0, 0, 0].repeat(100_000);
    c.send(&flood).expect("flood");
    assert!(
        c.read_tick().is_some(),
        "the flooding connection itself is served after"
    );
    srv.check_healthy(
        "malformed frames (lengths 0, 31, 4 GiB, 1 GiB, inconsistent)",
        rss,
    );
    // Counted in the whole log, read to its last line after the stop: a line still on its way
    // to stderr cannot be missed.
    let mut srv = srv;
    stop(&mut srv, "-TERM", Duration::from_secs(10));
    let log = srv.log_once_it_says("stopped after");
    let router_lines = log.matches("router command 0x9999").count();
    assert!(
        router_lines >= 1,
        "the unknown router frames are logged: {log}"
    );
    assert!(
        router_lines <= 5,
        "{router_lines} log lines for 100 000 router frames"
    );
    println!("ABUSE router flood: 100 000 unknown router frames, {router_lines} log line(s)");
}

#[test]
fn random_bytes_never_hurt_the_server() {
    let srv = Serve::start(&[]);
    let rss = srv.rss_kib();
    let mut gen = abuse_common::RandomBytes(0x9E37_79B9_7F4A_7C15);
    for i in 0..32 {
        let mut c = srv.connect();
        c.stream
            .set_write_timeout(Some(Duration::from_secs(2)))
            .expect("timeout");
        let mut junk = vec![0u8; 64 * 1024];
        gen.fill(&mut junk);
        if i % 2 == 0 {
            // Half the connections start with a valid AMS/TCP header, so the garbage is
            // taken as a frame body.
            junk[..6].copy_from_slice(&[0, 0, 0, 1, 0, 0]);
        }
        let _ = c.send(&junk);
        let _ = c.closed_within(Duration::from_millis(200));
    }
    srv.check_healthy("32 connections × 64 KiB of random bytes", rss);
}

#[test]
fn thousands_of_notification_requests_meet_the_whole_server_budget() {
    let srv = Serve::start(&[]);
    let rss = srv.rss_kib();
    let connections = 16;
    let per_connection = 200; // below the per-connection limit of 256
    let cycle_100ns = 100_000u32; // 10 ms: 100 samples/s a handle
    let add = add_notification_payload(cycle_100ns);
    let results: Vec<(usize, usize, Conn)> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..connections)
            .map(|_| {
                let add = add.clone();
                let srv = &srv;
                s.spawn(move || {
                    let mut c = srv.connect();
                    let (mut ok, mut full) = (0, 0);
                    for _ in 0..per_connection {
                        let d = c
                            .call(CommandId::AddDeviceNotification, &add)
                            .expect("AddDeviceNotification answered");
                        match u32_at(&d, 0) {
                            0 => ok += 1,
                            0x716 => full += 1,
                            other => panic!("unexpected result 0x{other:X}"),
                        }
                    }
                    (ok, full, c)
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("client"))
            .collect()
    });
    let ok: usize = results.iter().map(|r| r.0).sum();
    let full: usize = results.iter().map(|r| r.1).sum();
    let budget = ncchannel::vocab::ams::DEFAULT_NOTIFICATION_SAMPLES_PER_S as usize / 100;
    println!(
        "ABUSE notification flood: {} requests over {connections} connections: {ok} handles granted, {full} answered 0x716",
        connections * per_connection
    );
    assert_eq!(
        ok, budget,
        "the whole-server budget grants exactly {budget} 10 ms handles"
    );
    assert_eq!(ok + full, connections * per_connection);
    // Keep reading the samples while the cycle is measured.
    let stop = Arc::new(std::sync::atomic::AtomicBool::new(false));
    let readers: Vec<_> = results
        .into_iter()
        .map(|(_, _, mut c)| {
            let stop = Arc::clone(&stop);
            std::thread::spawn(move || {
                let mut chunk = [0u8; 65536];
                let mut samples_bytes = 0usize;
                let _ = c.stream.set_read_timeout(Some(Duration::from_millis(200)));
                while !stop.load(std::sync::atomic::Ordering::Relaxed) {
                    if let Ok(n) = c.stream.read(&mut chunk) {
                        samples_bytes += n;
                    }
                }
                samples_bytes
            })
        })
        .collect();
    srv.check_healthy(
        "16 connections × 200 notification requests (budget full)",
        rss,
    );
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    let bytes: usize = readers.into_iter().map(|r| r.join().unwrap_or(0)).sum();
    assert!(bytes > 0, "the granted handles send samples");
}

#[test]
fn idle_connections_are_closed_after_the_idle_timeout() {
    let srv = Serve::start(&["--ads-idle-timeout", "2"]);
    let rss = srv.rss_kib();
    let limit = ncchannel::vocab::ams::DEFAULT_MAX_CONNECTIONS;
    let started = Instant::now();
    let mut silent: Vec<Conn> = (0..limit).map(|_| srv.connect()).collect();
    // All slots held: a newcomer is refused (the listener accepts in connection order) ...
    let mut refused = srv.connect();
    assert!(
        refused.closed_within(Duration::from_secs(1)),
        "newcomer refused while full"
    );
    let log = srv.log_once_it_says("connection limit");
    assert!(log.contains("connection limit"), "{log}");
    // ... until the idle timeout frees them.
    for (i, c) in silent.iter_mut().enumerate() {
        assert!(
            c.closed_within(Duration::from_secs(15)),
            "silent connection {i} closed by the idle timeout"
        );
    }
    let freed = started.elapsed();
    assert!(served_again(&srv, Duration::from_secs(30)));
    let log = srv.log_once_it_says("idle for");
    assert!(log.contains("idle for"), "{log}");
    println!(
        "ABUSE idle connections: {limit} silent connections freed after {:.1} s (idle timeout 2 s)",
        freed.as_secs_f64()
    );
    srv.check_healthy("64 idle connections", rss);
}

/// Send `signal` to the serve process and wait for its exit status.
fn stop(srv: &mut Serve, signal: &str, within: Duration) -> std::process::ExitStatus {
    let ok = Command::new("kill")
        .args([signal, &srv.child.id().to_string()])
        .status()
        .expect("kill runs")
        .success();
    assert!(ok, "kill {signal}");
    let until = Instant::now() + within;
    loop {
        if let Some(s) = srv.child.try_wait().expect("try_wait") {
            return s;
        }
        assert!(
            Instant::now() < until,
            "serve did not stop within {within:?}"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn serve_seconds_inf_runs_until_a_signal() {
    let mut srv = Serve::start(&["--seconds", "inf"]);
    let rss = srv.rss_kib();
    srv.check_healthy("--seconds inf", rss);
    let status = stop(&mut srv, "-TERM", Duration::from_secs(10));
    let log = srv.log_once_it_says("stopped after");
    assert!(status.success(), "{status:?}\n{log}");
    assert!(log.contains("stopped after"), "{log}");
}

#[test]
fn events_into_a_pipe_nobody_reads_cost_counted_events_not_memory() {
    let rig = common::Rig::new();
    // Blocks without motion: some 40 a tick, each an event.
    rig.program("many.nc", &("G90\n".repeat(2_000_000) + "M30\n"));
    let mut srv = Serve::start_with(&rig.startup(), &["--start", "many.nc", "--events", "-"]);
    std::thread::sleep(Duration::from_secs(2));
    let rss = srv.rss_kib();
    std::thread::sleep(Duration::from_secs(4));
    let rss_later = srv.rss_kib();
    println!("ABUSE events into a pipe nobody reads: RSS {rss} KiB at 2 s, {rss_later} KiB at 6 s");
    assert!(
        rss_later <= rss + 16 * 1024,
        "the event queue grew from {rss} to {rss_later} KiB"
    );
    srv.check_healthy("--events - into a pipe nobody reads", rss);
    // The writer is stuck on the pipe: the stop gives it 5 s, then says what was lost.
    let status = stop(&mut srv, "-TERM", Duration::from_secs(20));
    let log = srv.log_once_it_says("stopped after");
    assert_eq!(status.code(), Some(1), "{log}");
    assert!(
        log.contains("the rest of the log was not written") && log.contains("events dropped"),
        "{log}"
    );
    assert!(log.contains("stopped after"), "{log}");
}

#[test]
fn frames_from_thousands_of_unrouted_net_ids_are_dropped_with_a_bounded_log() {
    // Only the normal client's NetId is routed; the rig's runtime.toml says so.
    let rig = common::Rig::with_runtime("[ads]\nallowed_clients = [\"127.0.0.1.1.1\"]\n");
    let srv = Serve::start_with(&rig.startup(), &[]);
    let rss = srv.rss_kib();
    let mut c = srv.connect();
    let mut bytes = Vec::new();
    for i in 0..20_000u32 {
        let [a, b, d, e] = i.to_le_bytes();
        let source = AmsAddr {
            net_id: AmsNetId([10, a, b, d, e, 1]),
            port: 40001,
        };
        bytes.extend(frame::encode(
            &AmsHeader {
                target: srv.device(),
                source,
                command: CommandId::ReadDeviceInfo,
                state_flags: frame::FLAGS_REQUEST,
                error: 0,
                invoke_id: i,
            },
            &[],
        ));
    }
    c.send(&bytes).expect("send");
    // The same connection, from the routed NetId, is still served.
    assert!(
        c.read_tick().is_some(),
        "routed frames after the unrouted ones"
    );
    let log = srv.log_once_it_says("no more are logged");
    assert!(log.contains("no more are logged"), "{log}");
    let named = log.matches("no route for source NetId").count();
    println!("ABUSE 20 000 unrouted source NetIds on one connection: {named} named in the log");
    assert!(named <= 16, "{named} NetIds logged");
    srv.check_healthy("20 000 unrouted source NetIds", rss);
}

#[test]
fn the_notification_budgets_are_runtime_toml_keys() {
    // Two 1 ms handles a connection, four over the server.
    let rig = common::Rig::with_runtime(
        "[ads]\nnotification_samples_per_s_per_connection = 2000\nnotification_samples_per_s = 4000\n",
    );
    let srv = Serve::start_with(&rig.startup(), &[]);
    let add = add_notification_payload(10_000); // 1 ms
    let results = |c: &mut Conn, n: usize| -> Vec<u32> {
        (0..n)
            .map(|_| {
                let d = c
                    .call(CommandId::AddDeviceNotification, &add)
                    .expect("answered");
                u32_at(&d, 0)
            })
            .collect()
    };
    let (mut first, mut second, mut third) = (srv.connect(), srv.connect(), srv.connect());
    assert_eq!(results(&mut first, 3), [0, 0, 0x716], "two a connection");
    assert_eq!(results(&mut second, 3), [0, 0, 0x716], "two a connection");
    assert_eq!(results(&mut third, 1), [0x716], "four over the server");

    // A connection's budget above the server's is refused when the file is read.
    let rig =
        common::Rig::with_runtime("[ads]\nnotification_samples_per_s_per_connection = 50000\n");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .args([
            "serve",
            "--bind",
            "127.0.0.1:0",
            "--seconds",
            "1",
            "--params",
        ])
        .arg(rig.startup())
        .output()
        .expect("serve runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("ads.notification_samples_per_s_per_connection: 50000 is above notification_samples_per_s (40000)"),
        "{err}"
    );
}

#[test]
fn a_client_that_never_reads_its_notifications_is_dropped() {
    let srv = Serve::start(&[]);
    let rss = srv.rss_kib();
    let mut c = srv.connect();
    let add = add_notification_payload(10_000); // 1 ms
    let mut granted = 0;
    for _ in 0..10 {
        let d = c
            .call(CommandId::AddDeviceNotification, &add)
            .expect("answered");
        granted += usize::from(u32_at(&d, 0) == 0);
    }
    assert!(granted > 0, "some 1 ms handles granted");
    // From now on nothing is read: the samples pile up in the kernel, then in the queue.
    // About 12 s on a quiet machine (socket buffers of a few MB fill at 10,000 samples/s);
    // the limit is only a safety net, wide enough for a machine whose cores are all busy
    // (90 s was once not enough under a parallel build).
    let started = Instant::now();
    while !srv.log().contains("does not read") && started.elapsed() < Duration::from_secs(300) {
        std::thread::sleep(Duration::from_millis(200));
    }
    let log = srv.log();
    assert!(log.contains("does not read"), "{log}");
    println!(
        "ABUSE notifications never read: {granted} handles at 1 ms, connection dropped after {:.1} s",
        started.elapsed().as_secs_f64()
    );
    drop(c);
    srv.check_healthy("a client that never reads its notifications", rss);
}
