//! Nothing holds a real `ncchannel serve`: its stderr a full pipe nobody reads, 64 connections
//! that hold their slots without making progress, and its stop on SIGTERM (how fast, and
//! without blaming clients for its own shutdown). Bounds in docs/ads-limits.md.

use std::io::{BufRead, BufReader, Write};
use std::process::{Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use ncchannel::ads::frame::CommandId;

use crate::ads_abuse::{add_notification_payload, request, Conn, Serve};

/// Send SIGTERM and measure, polling the process every millisecond, how long it takes to exit.
fn sigterm_exit_time(srv: &mut Serve, within: Duration) -> (std::process::ExitStatus, Duration) {
    let ok = Command::new("kill")
        .args(["-TERM", &srv.child.id().to_string()])
        .status()
        .expect("kill runs")
        .success();
    assert!(ok, "kill -TERM");
    let sent = Instant::now();
    loop {
        if let Some(s) = srv.child.try_wait().expect("try_wait") {
            return (s, sent.elapsed());
        }
        assert!(
            sent.elapsed() < within,
            "serve did not stop within {within:?}"
        );
        std::thread::sleep(Duration::from_millis(1));
    }
}

#[test]
fn sigterm_stops_serve_at_once_and_logs_no_client_fault_for_its_own_shutdown() {
    let mut srv = Serve::start(&[]);
    // Clients in every state: one with a notification at 1 ms, one idle, one mid-request.
    let mut notified = srv.connect();
    let add = add_notification_payload(10_000);
    let d = notified
        .call(CommandId::AddDeviceNotification, &add)
        .expect("answered");
    assert_eq!(ads_u32(&d, 0), 0, "notification granted");
    let mut idle = srv.connect();
    assert!(idle.read_tick().is_some());
    let mut mid = srv.connect();
    let half = request(srv.device(), CommandId::ReadDeviceInfo, 1, &[]);
    mid.send(&half[..10]).expect("send");
    let (status, took) = sigterm_exit_time(&mut srv, Duration::from_secs(10));
    println!(
        "SIGTERM: serve exited {:.1} ms after the signal",
        took.as_secs_f64() * 1e3
    );
    assert!(status.success(), "{status:?}\n{}", srv.log());
    // Generous against a loaded machine; the figure above is what it takes.
    assert!(took < Duration::from_secs(2), "exit took {took:?}");
    let log = crate::support::abuse::log_once_it_holds(
        &srv.stderr,
        "stopped after",
        1,
        Duration::from_secs(30),
    );
    assert!(log.contains("stopped after"), "{log}");
    assert!(!log.contains("does not read"), "{log}");
    drop((notified, idle, mid));
}

fn ads_u32(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"))
}

#[test]
fn with_stderr_a_full_pipe_nobody_reads_clients_are_served_and_sigterm_stops_serve() {
    let turn = crate::ads_abuse::turn();
    let (reader, writer) = std::io::pipe().expect("pipe");
    let child = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args([
            "serve",
            "--bind",
            "127.0.0.1:0",
            "--params",
            "params/startup.lis",
        ])
        .stdout(Stdio::null())
        .stderr(writer.try_clone().expect("clone"))
        .spawn()
        .expect("ncchannel serve starts");
    let mut reader = BufReader::new(reader);
    let mut first = String::new();
    reader.read_line(&mut first).expect("first line");
    let mut srv = Serve::from_child(turn, child, &first, Arc::new(Mutex::new(String::new())));
    // Fill the pipe from here (the write end is shared with serve), then nobody reads it: a
    // supervisor that stopped reading. The filler blocks once the pipe is full.
    let filled = Arc::new(Mutex::new(0usize));
    let counter = Arc::clone(&filled);
    let mut filler = writer;
    std::thread::spawn(move || {
        let line = [b'x'; 1024];
        while filler.write_all(&line).is_ok() {
            *counter.lock().unwrap() += line.len();
        }
    });
    let until = Instant::now() + Duration::from_secs(30);
    let mut last = 0;
    loop {
        std::thread::sleep(Duration::from_millis(100));
        let now = *filled.lock().unwrap();
        if now > 0 && now == last {
            break; // the filler is blocked: the pipe is full
        }
        last = now;
        assert!(Instant::now() < until, "pipe never filled");
    }
    // 1,200 connections, each ending with a line the server logs (a malformed frame).
    let started = Instant::now();
    let mut served = 0;
    for i in 0..1200 {
        let mut c = srv.connect();
        assert!(c.read_tick().is_some(), "connection {i} served");
        served += 1;
        let _ = c.send(&[0xFF; 6]); // AMS/TCP reserved bytes not zero: closed, with a line
        assert!(
            c.closed_within(Duration::from_secs(5)),
            "connection {i} closed"
        );
    }
    println!(
        "FULL STDERR: {served} connections served and closed with a log line each in {:.1} s ({} KiB of stderr filled, unread)",
        started.elapsed().as_secs_f64(),
        last / 1024
    );
    let rss = srv.rss_kib();
    srv.check_healthy("stderr a full pipe", rss);
    let (status, took) = sigterm_exit_time(&mut srv, Duration::from_secs(10));
    println!(
        "FULL STDERR: SIGTERM exit after {:.1} ms",
        took.as_secs_f64() * 1e3
    );
    assert!(status.success(), "{status:?}");
    assert!(took < Duration::from_secs(2), "exit took {took:?}");
    drop(reader);
}

/// A frame that is never finished: one byte of it now and then.
fn trickle(mut c: Conn, device: ncchannel::ads::frame::AmsAddr, stop: Arc<Mutex<bool>>) {
    let frame = request(device, CommandId::ReadDeviceInfo, 7, &[]);
    for b in frame.iter().take(frame.len() - 1) {
        if *stop.lock().unwrap() || c.send(&[*b]).is_err() {
            return;
        }
        std::thread::sleep(Duration::from_millis(500));
    }
}

#[test]
fn sixty_four_connections_that_make_no_progress_give_way_to_a_new_client() {
    let srv = Serve::start(&[]);
    let rss = srv.rss_kib();
    let limit = ncchannel::vocab::ams::DEFAULT_MAX_CONNECTIONS;
    let stop_all = Arc::new(Mutex::new(false));
    let mut holders = Vec::new();
    let mut tricklers = Vec::new();
    for i in 0..limit {
        let mut c = srv.connect();
        // Each completes one request (as a client completing one frame per idle period) ...
        assert!(
            c.read_tick().is_some(),
            "hostile connection {i} served once"
        );
        match i % 3 {
            // ... then holds a notification and never reads,
            0 => {
                let add = add_notification_payload(100_000); // 10 ms
                assert!(c.call(CommandId::AddDeviceNotification, &add).is_some());
                holders.push(c);
            }
            // ... or trickles one byte of its next frame every 500 ms,
            1 => {
                let (device, stop) = (srv.device(), Arc::clone(&stop_all));
                tricklers.push(std::thread::spawn(move || trickle(c, device, stop)));
            }
            // ... or sends AMS router commands nobody answers, ten a second.
            _ => {
                let stop = Arc::clone(&stop_all);
                tricklers.push(std::thread::spawn(move || {
                    while !*stop.lock().unwrap() && c.send(&[0xFF, 0x0F, 0, 0, 0, 0]).is_ok() {
                        std::thread::sleep(Duration::from_millis(100));
                    }
                }));
            }
        }
    }
    // The 65th, an honest client, is served once the hostile ones have gone without progress
    // for the eviction threshold; until then it is refused at once and tries again.
    let asked = Instant::now();
    let deadline = asked + ncchannel::ads::EVICT_QUIET + Duration::from_secs(30);
    let served_after = loop {
        if srv.connect().read_tick().is_some() {
            break asked.elapsed();
        }
        assert!(Instant::now() < deadline, "honest client never served");
        std::thread::sleep(Duration::from_millis(200));
    };
    println!(
        "HOSTILE SLOTS: {limit} held without progress; the 65th client served after {:.1} s (eviction after {} s quiet)",
        served_after.as_secs_f64(),
        ncchannel::ads::EVICT_QUIET.as_secs()
    );
    let log = crate::support::abuse::log_once_it_holds(
        &srv.stderr,
        "closed to serve",
        1,
        Duration::from_secs(30),
    );
    assert!(log.contains("closed to serve"), "{log}");
    srv.check_healthy("64 connections without progress", rss);
    *stop_all.lock().unwrap() = true;
    drop(holders);
    for t in tricklers {
        let _ = t.join();
    }
}

/// Connections that connect and never send a byte, 60 a second (a port scanner, a crashed
/// client's reconnect loop): a client that connects meanwhile and reads must still be served.
/// A connection that has not completed a request within `ads::FIRST_REQUEST_GRACE` gives its
/// slot up before any connection that has (docs/ads-limits.md, "Slots").
#[test]
fn connection_churn_that_never_sends_does_not_lock_out_a_client() {
    const CHURN_PER_S: u64 = 60;
    const PROBES: usize = 30;
    let srv = Serve::start(&[]);
    let addr = srv.addr();
    let stop = Arc::new(Mutex::new(false));
    let churn = {
        let stop = Arc::clone(&stop);
        std::thread::spawn(move || {
            // Kept open (never a byte sent) until the end; the server closes those it evicts.
            let mut held = Vec::new();
            let start = Instant::now();
            let mut n = 0u64;
            while !*stop.lock().unwrap() && held.len() < 2_000 {
                if let Ok(s) = std::net::TcpStream::connect(addr) {
                    held.push(s);
                }
                n += 1;
                let next = start + Duration::from_micros(n * 1_000_000 / CHURN_PER_S);
                std::thread::sleep(next.saturating_duration_since(Instant::now()));
            }
            held.len()
        })
    };
    // The table is full after a little over a second of churn (64 slots at 60 a second).
    std::thread::sleep(Duration::from_millis(1_500));
    let mut served = 0usize;
    for _ in 0..PROBES {
        if srv.connect().read_tick().is_some() {
            served += 1;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    *stop.lock().unwrap() = true;
    let churned = churn.join().expect("churn thread");
    println!(
        "CHURN: {churned} connections at {CHURN_PER_S}/s that never sent a byte; {served} of {PROBES} probes served"
    );
    assert!(
        served >= PROBES * 9 / 10,
        "only {served} of {PROBES} probes served under churn\n{}",
        srv.log()
    );
    let log = srv.log_once_it_says("closed to serve");
    assert!(log.contains("no request since it connected"), "{log}");
}
