//! Slowloris: clients that hold every connection slot trickling request heads do not lock a
//! page out; the oldest unfinished head gives way to a newcomer, and a head that trickles
//! past the request deadline is dropped whole.

use std::io::Write;
use std::net::TcpStream;
use std::time::{Duration, Instant};

use ncchannel::http::{ControlAccess, MAX_CONNECTIONS};

use super::client;
use super::view;

const WITHIN: Duration = Duration::from_secs(20);
const PROBES: usize = 10;

/// Wait (bounded) until the view counts `n` open connections.
fn until_open(web: &ncchannel::http::HttpHandle, n: usize) {
    let end = Instant::now() + WITHIN;
    while web.connections_open() < n {
        assert!(
            Instant::now() < end,
            "{} of {n} connections open",
            web.connections_open()
        );
        std::thread::yield_now();
    }
}

#[test]
fn a_probe_is_served_while_every_slot_trickles_a_head() {
    let (web, _channels) = view(ControlAccess::Refused);
    let addr = web.local_addr();
    let mut slow: Vec<TcpStream> = Vec::new();
    let mut served = 0;
    for _ in 0..PROBES {
        // The attacker keeps every slot busy with a head that never ends, one byte at a time.
        slow.retain_mut(|s| s.write_all(b"X").is_ok());
        while slow.len() < MAX_CONNECTIONS {
            let mut s = TcpStream::connect(addr).expect("loopback connect");
            s.write_all(b"G").expect("first byte");
            slow.push(s);
        }
        until_open(&web, MAX_CONNECTIONS);
        let probe = std::panic::catch_unwind(|| client::get(addr, "/controls"));
        if probe.is_ok_and(|r| r.status == 200) {
            served += 1;
        }
        // Whoever was evicted sees its connection closed; drop the dead ones next round.
        slow.retain_mut(|s| s.write_all(b"E").is_ok() && s.flush().is_ok());
    }
    println!("slowloris probe: {served} of {PROBES} served with {MAX_CONNECTIONS} slow heads");
    assert_eq!(served, PROBES);
}
