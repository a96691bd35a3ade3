//! ADS housekeeping real clients rely on: AMS/TCP port close (0x0001) ends the port's
//! notifications and closes the connection at once; the 257th notification handle answers
//! 0x716 (no more handles); a notification's first sample follows the AddDeviceNotification
//! response, never precedes it.

use std::time::{Duration, Instant};

use crate::support::ads::*;
use ncchannel::ads::objects::offset;
use ncchannel::ads::payload::request;

const ADD_NOTIFICATION: u16 = 6;
const DEVICE_NOTIFICATION: u16 = 8;

fn add(raw: &mut Raw, invoke: u32, mode: u32, cycle_100ns: u32) {
    let req = request::add_notification(CH1, offset::BLOCK_COUNTER, 8, mode, 0, cycle_100ns);
    raw.send(&request_bytes(
        ADD_NOTIFICATION,
        device(),
        client_addr(40000),
        invoke,
        &req,
    ));
}

#[test]
fn the_257th_notification_handle_answers_no_more_handles() {
    let (srv, _b) = server();
    let mut raw = Raw::connect(srv.local_addr());
    let mut results = Vec::new();
    for invoke in 1..=257 {
        // On change (4), 1 s: one sample each, then quiet.
        add(&mut raw, invoke, 4, 10_000_000);
        loop {
            let (h, d) = raw.frame();
            if h.command.to_u16() == ADD_NOTIFICATION {
                results.push(u32_at(&d, 0));
                break;
            }
        }
    }
    assert!(results[..256].iter().all(|&r| r == 0));
    assert_eq!(results[256], 0x716, "ADSERR_DEVICE_NOMOREHDLS");
}

#[test]
fn the_first_sample_follows_the_add_response() {
    let (srv, _b) = server();
    let mut delays = Vec::new();
    for invoke in 1..=30 {
        // A connection of its own each round: no older handle's samples in between.
        let mut raw = Raw::connect(srv.local_addr());
        // On change (4) with a 10 s cycle: the only sample within the round is the first one,
        // sent after the response, never before it.
        add(&mut raw, invoke, 4, 100_000_000);
        let (h, _) = raw.frame();
        assert_eq!(
            h.command.to_u16(),
            ADD_NOTIFICATION,
            "response before any sample (round {invoke})"
        );
        let answered = Instant::now();
        let (h, _) = raw.frame();
        assert_eq!(
            h.command.to_u16(),
            DEVICE_NOTIFICATION,
            "the first sample next (round {invoke})"
        );
        delays.push(answered.elapsed());
    }
    delays.sort();
    println!(
        "FIRST SAMPLE after the add's response: median {:.2} ms, max {:.2} ms (30 rounds)",
        delays[15].as_secs_f64() * 1e3,
        delays[29].as_secs_f64() * 1e3
    );
}

#[test]
fn port_close_ends_notifications_and_closes_the_connection_at_once() {
    let (srv, _b) = server();
    let mut raw = Raw::connect(srv.local_addr());
    add(&mut raw, 1, 3, 100_000);
    loop {
        let (h, _) = raw.frame();
        if h.command.to_u16() == DEVICE_NOTIFICATION {
            break;
        }
    }
    // AMS/TCP header: command 0x0001, length 2, the port.
    let mut close = vec![0x01, 0x00, 2, 0, 0, 0];
    close.extend_from_slice(&40000u16.to_le_bytes());
    let sent = Instant::now();
    raw.send(&close);
    assert!(
        raw.closed_within(Duration::from_secs(1)),
        "connection closed"
    );
    assert!(sent.elapsed() < Duration::from_secs(1));
    // The server goes on serving others.
    let mut other = Raw::connect(srv.local_addr());
    let (_, d) = other.call(2, 1, &read_req(CH1, offset::BLOCK_COUNTER, 8));
    assert_eq!(u32_at(&d, 0), 0);
}
