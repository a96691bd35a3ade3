//! ADS abuse on loopback, each bounded in count and time: silent connections that hold every
//! slot, a client trickling one byte at a time, frames with lengths 0, huge and inconsistent,
//! random bytes, unknown router commands, and notification requests beyond the whole server's
//! budget. After each, a normal client is served at once.

mod ads_common;

use std::io::Write;
use std::time::{Duration, Instant};

use ads_common::*;
use ncchannel::ads::memory::DrainRate;
use ncchannel::ads::objects::offset;
use ncchannel::ads::payload::request;
use ncchannel::ads::server::FRAME_DEADLINE;
use ncchannel::ads::ServerConfig;

const READ: u16 = 2;
const ADD_NOTIFICATION: u16 = 6;
const DEL_NOTIFICATION: u16 = 7;

/// A normal client's read of the block counter: answered, result 0.
fn served(addr: std::net::SocketAddr) -> bool {
    let mut raw = Raw::connect(addr);
    raw.send(&request_bytes(
        READ,
        device(),
        client_addr(40000),
        1,
        &read_req(CH1, offset::BLOCK_COUNTER, 8),
    ));
    match raw.frame_bytes(Duration::from_secs(5)) {
        Some(b) => u32_at(&b, 38) == 0,
        None => false,
    }
}

#[test]
fn silent_connections_cannot_hold_the_slots() {
    let (srv, _b) = server_with(
        ServerConfig {
            max_connections: 4,
            ..ServerConfig::default()
        },
        DrainRate::default(),
    );
    let addr = srv.local_addr();
    let mut silent: Vec<Raw> = (0..4).map(|_| Raw::connect(addr)).collect();
    // Every slot is held: the next connection is closed at once.
    let deadline = Instant::now() + Duration::from_secs(5);
    while srv.connections() < 4 && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(10));
    }
    let mut extra = Raw::connect(addr);
    assert!(
        extra.closed_within(Duration::from_secs(5)),
        "over the limit"
    );
    // The silent ones are closed once the first-frame deadline passes; then a client is served.
    let started = Instant::now();
    for s in &mut silent {
        assert!(s.closed_within(FRAME_DEADLINE + Duration::from_secs(10)));
    }
    let waited = started.elapsed();
    assert!(
        waited <= FRAME_DEADLINE + Duration::from_secs(10),
        "{waited:?}"
    );
    assert!(served(addr), "a normal client after the silent ones");
}

#[test]
fn a_client_trickling_a_frame_is_closed_and_others_are_served_meanwhile() {
    let (srv, _b) = server();
    let addr = srv.local_addr();
    let frame = request_bytes(
        READ,
        device(),
        client_addr(40000),
        7,
        &read_req(CH1, offset::BLOCK_COUNTER, 8),
    );
    let mut slow = Raw::connect(addr);
    // One byte every 0.5 s: the 50-byte frame would take 25 s.
    let started = Instant::now();
    let mut cut = false;
    for b in &frame {
        if slow.stream.write_all(&[*b]).is_err() {
            cut = true;
            break;
        }
        assert!(served(addr), "served while the trickle goes on");
        if started.elapsed() > FRAME_DEADLINE + Duration::from_secs(5) {
            break;
        }
        std::thread::sleep(Duration::from_millis(500));
    }
    assert!(
        cut || slow.closed_within(Duration::from_secs(5)),
        "trickler closed"
    );
    assert!(started.elapsed() < FRAME_DEADLINE + Duration::from_secs(8));
}

#[test]
fn malformed_frames_and_random_bytes_close_only_their_own_connection() {
    let (srv, _b) = server();
    let addr = srv.local_addr();
    let good = request_bytes(
        READ,
        device(),
        client_addr(40000),
        1,
        &read_req(CH1, offset::BLOCK_COUNTER, 8),
    );
    let mut inconsistent = good.clone();
    // AMS data length says 4 more bytes than the frame holds.
    let n = u32::from_le_bytes(inconsistent[26..30].try_into().unwrap());
    inconsistent[26..30].copy_from_slice(&(n + 4).to_le_bytes());
    let mut rng = 0x9E37_79B9_7F4A_7C15u64;
    let random: Vec<u8> = (0..4096)
        .map(|_| {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            rng as u8
        })
        .collect();
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("length 0", vec![0, 0, 0, 0, 0, 0]),
        ("huge length", vec![0, 0, 0xFF, 0xFF, 0xFF, 0xFF]),
        ("inconsistent AMS length", inconsistent),
        ("random bytes", random),
    ];
    for (what, bytes) in cases {
        let mut raw = Raw::connect(addr);
        let _ = raw.stream.write_all(&bytes);
        // Either closed, or left waiting for the rest (then the frame deadline closes it).
        let closed = raw.closed_within(FRAME_DEADLINE + Duration::from_secs(5));
        assert!(closed, "{what}: connection closed");
        assert!(served(addr), "{what}: a normal client is served after it");
    }
    // Thousands of unknown router commands: ignored, the connection stays usable.
    let mut raw = Raw::connect(addr);
    for _ in 0..5000 {
        raw.send(&[0x34, 0x12, 0, 0, 0, 0]);
    }
    raw.send(&good);
    let (h, d) = raw.frame();
    assert_eq!((h.command.to_u16(), u32_at(&d, 0)), (READ, 0));
}

fn add(raw: &mut Raw, invoke: u32, cycle_100ns: u32) -> (u32, u32) {
    let req = request::add_notification(CH1, offset::BLOCK_COUNTER, 8, 3, 0, cycle_100ns);
    raw.send(&request_bytes(
        ADD_NOTIFICATION,
        device(),
        client_addr(40000),
        invoke,
        &req,
    ));
    loop {
        let (h, d) = raw.frame();
        if h.command.to_u16() == ADD_NOTIFICATION {
            return (u32_at(&d, 0), u32_at(&d, 4));
        }
    }
}

#[test]
fn notifications_of_all_connections_share_one_budget() {
    // 3,000 samples/s for the whole server: three handles at 1 ms fit, a fourth does not —
    // on whichever connection it is asked for.
    let (srv, _b) = server_with(
        ServerConfig {
            max_notification_rate_per_s: 3000,
            ..ServerConfig::default()
        },
        DrainRate::default(),
    );
    let addr = srv.local_addr();
    let mut a = Raw::connect(addr);
    let mut b = Raw::connect(addr);
    let (r1, h1) = add(&mut a, 1, 10_000);
    let (r2, _) = add(&mut a, 2, 10_000);
    let (r3, _) = add(&mut b, 3, 10_000);
    assert_eq!((r1, r2, r3), (0, 0, 0));
    assert_eq!(
        add(&mut b, 4, 10_000).0,
        0x716,
        "beyond the server's budget"
    );
    // A slow handle (1 s) costs one sample per second: still room for it? No: the budget is
    // exactly spent. After a delete there is room again.
    let req = h1.to_le_bytes();
    a.send(&request_bytes(
        DEL_NOTIFICATION,
        device(),
        client_addr(40000),
        9,
        &req,
    ));
    loop {
        let (h, d) = a.frame();
        if h.command.to_u16() == DEL_NOTIFICATION {
            assert_eq!(u32_at(&d, 0), 0);
            break;
        }
    }
    assert_eq!(add(&mut b, 5, 10_000).0, 0, "room after a delete");
    // A closed connection gives its handles back.
    drop(a);
    std::thread::sleep(Duration::from_millis(700));
    assert_eq!(
        add(&mut b, 6, 10_000).0,
        0,
        "room after a connection closed"
    );
    assert!(served(addr));
}
