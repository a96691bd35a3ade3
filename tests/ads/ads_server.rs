//! The ADS server on the wire: framing, address swap, echo, exact sizes, bad frames, limits,
//! notifications and the route allow-list (docs/ads-wire.md), against real channels ticking
//! at 1 ms behind the server (tests/ads_common).

use std::time::{Duration, Instant};

use crate::support::ads::*;
use ncchannel::ads::frame::AmsAddr;
use ncchannel::ads::objects::offset;
use ncchannel::ads::payload::{self, request};
use ncchannel::ads::{RouteEntry, ServerConfig};

const READ_DEVICE_INFO: u16 = 1;
const READ: u16 = 2;
const WRITE: u16 = 3;
const READ_STATE: u16 = 4;
const WRITE_CONTROL: u16 = 5;
const ADD_NOTIFICATION: u16 = 6;
const DEL_NOTIFICATION: u16 = 7;
const READ_WRITE: u16 = 9;

#[test]
fn a_request_sent_byte_by_byte_is_answered_once_complete() {
    let (srv, _b) = server();
    let mut raw = Raw::connect(srv.local_addr());
    let req = request_bytes(READ_STATE, device(), client_addr(40000), 77, &[]);
    for b in &req[..req.len() - 1] {
        raw.send(&[*b]);
        std::thread::sleep(Duration::from_micros(200));
    }
    assert!(
        raw.frame_bytes(Duration::from_millis(100)).is_none(),
        "answered an incomplete frame"
    );
    raw.send(&req[req.len() - 1..]);
    let (h, data) = raw.frame();
    assert_eq!(h.invoke_id, 77);
    assert_eq!(data, [0, 0, 0, 0, 5, 0, 0, 0]); // result 0, ADS state RUN, device state 0
}

#[test]
fn several_frames_in_one_write_are_all_answered_in_order() {
    let (srv, _b) = server();
    let mut raw = Raw::connect(srv.local_addr());
    let mut burst = Vec::new();
    for invoke in 1..=5u32 {
        burst.extend(request_bytes(
            READ_STATE,
            device(),
            client_addr(40000),
            invoke,
            &[],
        ));
    }
    // and half of a sixth
    let sixth = request_bytes(READ_STATE, device(), client_addr(40000), 6, &[]);
    burst.extend_from_slice(&sixth[..10]);
    raw.send(&burst);
    for invoke in 1..=5u32 {
        assert_eq!(raw.frame().0.invoke_id, invoke);
    }
    raw.send(&sixth[10..]);
    assert_eq!(raw.frame().0.invoke_id, 6);
}

#[test]
fn response_swaps_addresses_byte_for_byte_and_echoes_command_and_invoke_id() {
    let (srv, _b) = server();
    let mut raw = Raw::connect(srv.local_addr());
    let req = request_bytes(
        READ,
        device(),
        client_addr(40123),
        0xCAFE_F00D,
        &read_req(CH1, offset::MODE_STATE, 8),
    );
    raw.send(&req);
    let resp = raw.frame_bytes(Duration::from_secs(5)).unwrap();
    assert_eq!(&resp[0..2], &[0, 0], "reserved");
    assert_eq!(resp[6..14], req[14..22], "response target = request source");
    assert_eq!(resp[14..22], req[6..14], "response source = request target");
    assert_eq!(resp[22..24], req[22..24], "command echoed");
    assert_eq!(resp[24..26], [5, 0], "flags exactly 0x0005");
    assert_eq!(resp[34..38], req[34..38], "invoke id echoed");
    let data_len = u32_at(&resp, 26) as usize;
    assert_eq!(
        u32_at(&resp, 2) as usize,
        32 + data_len,
        "AMS/TCP length = 32 + n"
    );
    assert_eq!(resp.len(), 38 + data_len);
    assert_eq!(u32_at(&resp, 30), 0, "no header error");
    // result 0, length 8, mode AUTOMATIC (2), state READY (3)
    assert_eq!(
        &resp[38..],
        &[0, 0, 0, 0, 8, 0, 0, 0, 2, 0, 0, 0, 3, 0, 0, 0]
    );
}

#[test]
fn response_sizes_are_exact() {
    let (srv, b) = server();
    let mut raw = Raw::connect(srv.local_addr());
    let (_, d) = raw.call(READ_DEVICE_INFO, 1, &[]);
    assert_eq!(d.len(), 24);
    let name: Vec<u8> = d[8..].iter().copied().take_while(|&c| c != 0).collect();
    assert_eq!(
        String::from_utf8(name).unwrap(),
        format!("ncchannel {}", env!("CARGO_PKG_VERSION"))
    );

    let (_, d) = raw.call(WRITE, 2, &write_req(CH1, offset::STREAM, b"N10 X1\r\n"));
    assert_eq!(d, [0, 0, 0, 0], "Write response is exactly the result");

    let (_, d) = raw.call(READ_STATE, 3, &[]);
    assert_eq!(d.len(), 8);

    // A text object read with a short length is cut to that length: never more than asked.
    raw.call(WRITE, 4, &write_req(CH1, offset::STREAM, b"no line end"));
    for asked in [0u32, 5, 40, 1000] {
        let (_, d) = raw.call(READ, 5, &read_req(CH1, offset::ERROR_MESSAGE, asked));
        assert!(
            d.len() <= 8 + asked as usize,
            "asked {asked}, got {}",
            d.len()
        );
        assert_eq!(u32_at(&d, 4) as usize, d.len() - 8);
    }
    let (_, d) = raw.call(READ, 6, &read_req(CH1, offset::ERROR_MESSAGE, 1000));
    assert!(
        String::from_utf8_lossy(&d[8..]).starts_with("21476 "),
        "{d:?}"
    );
    // A fixed-size object read with more room answers with its own size.
    let (_, d) = raw.call(READ, 7, &read_req(CH1, offset::BLOCK_COUNTER, 64));
    assert_eq!(d.len(), 16);
    drop(b);
}

#[test]
fn several_source_ports_share_one_connection() {
    let (srv, _b) = server();
    let mut raw = Raw::connect(srv.local_addr());
    let ports = [30001u16, 851, 40002, 30001];
    let mut burst = Vec::new();
    for (i, &p) in ports.iter().enumerate() {
        burst.extend(request_bytes(
            READ_STATE,
            device(),
            client_addr(p),
            i as u32 + 100,
            &[],
        ));
    }
    raw.send(&burst);
    for (i, &p) in ports.iter().enumerate() {
        let (h, _) = raw.frame();
        assert_eq!(h.target, client_addr(p));
        assert_eq!(h.source, device());
        assert_eq!(h.invoke_id, i as u32 + 100);
    }
}

#[test]
fn many_connections_are_served_at_once() {
    let (srv, _b) = server();
    let addr = srv.local_addr();
    let threads: Vec<_> = (0..24u32)
        .map(|t| {
            std::thread::spawn(move || {
                let mut raw = Raw::connect(addr);
                for i in 0..20u32 {
                    let invoke = t * 1000 + i;
                    let (h, d) = raw.call(READ, invoke, &read_req(CH1, offset::MODE_STATE, 8));
                    assert_eq!(h.invoke_id, invoke);
                    assert_eq!(d.len(), 16);
                }
            })
        })
        .collect();
    for t in threads {
        t.join().unwrap();
    }
}

#[test]
fn connections_beyond_the_limit_are_closed_and_the_others_keep_working() {
    let cfg = ServerConfig {
        max_connections: 2,
        ..ServerConfig::default()
    };
    let (srv, _b) = server_with(cfg);
    let mut a = Raw::connect(srv.local_addr());
    let mut b = Raw::connect(srv.local_addr());
    a.call(READ_STATE, 1, &[]);
    b.call(READ_STATE, 1, &[]);
    let mut c = Raw::connect(srv.local_addr());
    assert!(c.closed_within(Duration::from_secs(10)));
    assert_eq!(a.call(READ_STATE, 2, &[]).0.invoke_id, 2);
    drop(a);
    // The freed slot is usable again once the server has seen the close.
    let deadline = Instant::now() + Duration::from_secs(30);
    while srv.connections() > 1 && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(
        srv.connections(),
        1,
        "the closed connection's slot is freed"
    );
    let mut d = Raw::connect(srv.local_addr());
    assert_eq!(d.call(READ_STATE, 3, &[]).0.invoke_id, 3);
}

#[test]
fn oversized_and_short_frames_close_only_their_connection() {
    let (srv, _b) = server();
    let mut good = Raw::connect(srv.local_addr());

    let mut huge = Raw::connect(srv.local_addr());
    let mut hdr = vec![0u8, 0];
    hdr.extend_from_slice(&(10_000_000u32).to_le_bytes());
    huge.send(&hdr);
    assert!(
        huge.closed_within(Duration::from_secs(10)),
        "oversized length must close"
    );

    let mut short = Raw::connect(srv.local_addr());
    let mut bad = vec![0u8, 0];
    bad.extend_from_slice(&8u32.to_le_bytes());
    bad.extend_from_slice(&[0; 8]);
    short.send(&bad);
    assert!(
        short.closed_within(Duration::from_secs(10)),
        "length < 32 must close"
    );

    let mut lying = Raw::connect(srv.local_addr());
    let mut f = request_bytes(READ_STATE, device(), client_addr(1), 1, &[]);
    f[26] = 50; // AMS data length disagrees with the AMS/TCP length
    lying.send(&f);
    assert!(lying.closed_within(Duration::from_secs(10)));

    assert_eq!(good.call(READ_STATE, 9, &[]).0.invoke_id, 9);
}

#[test]
fn short_payloads_are_answered_0x705() {
    let (srv, _b) = server();
    let mut raw = Raw::connect(srv.local_addr());
    let (h, d) = raw.call(READ, 1, &[1, 2, 3]);
    assert_eq!(h.error, 0);
    assert_eq!(u32_at(&d, 0), 0x705);
    let (_, d) = raw.call(WRITE, 2, &[0; 11]);
    assert_eq!(d, 0x705u32.to_le_bytes());
    // Declared write length larger than the data present.
    let mut w = write_req(CH1, offset::STREAM, b"N1\r\n");
    w[8] = 100;
    let (_, d) = raw.call(WRITE, 3, &w);
    assert_eq!(d, 0x705u32.to_le_bytes());
    let (_, d) = raw.call(DEL_NOTIFICATION, 4, &[1]);
    assert_eq!(d, 0x705u32.to_le_bytes());
}

#[test]
fn unknown_command_is_0x701_and_unknown_port_is_header_error_6() {
    let (srv, _b) = server();
    let mut raw = Raw::connect(srv.local_addr());
    let (h, d) = raw.call(0x55, 1, &[1, 2, 3, 4]);
    assert_eq!(h.error, 0);
    assert_eq!(d, 0x701u32.to_le_bytes());

    let plc = AmsAddr {
        port: 800,
        ..device()
    };
    raw.send(&request_bytes(
        READ,
        plc,
        client_addr(40000),
        2,
        &read_req(CH1, offset::MODE_STATE, 8),
    ));
    let bytes = raw.frame_bytes(Duration::from_secs(5)).unwrap();
    assert_eq!(u32_at(&bytes, 30), 6, "AMS header error 6");
    assert_eq!(u32_at(&bytes, 26), 0, "empty payload");
    assert_eq!(bytes.len(), 38);
    assert_eq!(u32_at(&bytes, 34), 2);
}

#[test]
fn write_control_on_the_cnc_task_keeps_it_running_and_refuses_unknown_states() {
    let (srv, _b) = server();
    let mut raw = Raw::connect(srv.local_addr());
    let mut wc = vec![5, 0, 0, 0];
    wc.extend_from_slice(&0u32.to_le_bytes());
    assert_eq!(raw.call(WRITE_CONTROL, 1, &wc).1, [0, 0, 0, 0]);
    wc[0] = 6; // STOP: every channel reset, the task runs on
    assert_eq!(raw.call(WRITE_CONTROL, 2, &wc).1, [0, 0, 0, 0]);
    assert_eq!(raw.call(READ_STATE, 3, &[]).1, [0, 0, 0, 0, 5, 0, 0, 0]);
    wc[0] = 99;
    assert_eq!(raw.call(WRITE_CONTROL, 4, &wc).1, 0x706u32.to_le_bytes());
}

#[test]
fn configured_net_id_answers_other_machines_with_error_7() {
    let cfg = ServerConfig {
        net_id: Some(device().net_id),
        ..ServerConfig::default()
    };
    let (srv, _b) = server_with(cfg);
    let mut raw = Raw::connect(srv.local_addr());
    assert_eq!(raw.call(READ_STATE, 1, &[]).0.error, 0);
    let other = AmsAddr {
        net_id: "1.1.1.1.1.1".parse().unwrap(),
        port: 553,
    };
    raw.send(&request_bytes(READ_STATE, other, client_addr(1), 2, &[]));
    assert_eq!(raw.frame().0.error, 7);
}

fn result_of_write(raw: &mut Raw, group: u32, off: u32, data: &[u8]) -> u32 {
    u32_at(&raw.call(WRITE, 1, &write_req(group, off, data)).1, 0)
}

fn result_of_read(raw: &mut Raw, group: u32, off: u32, len: u32) -> (u32, Vec<u8>) {
    let (_, d) = raw.call(READ, 1, &read_req(group, off, len));
    (u32_at(&d, 0), d[8..].to_vec())
}

#[test]
fn stream_object_results_follow_the_buffer() {
    let (srv, channels) = server();
    let mut raw = Raw::connect(srv.local_addr());
    let packet = [vec![b'X'; 990], b"\r\n".to_vec()].concat();
    // The channel is not running, so nothing drains: 4 × 992 fit in 4094, the 5th does not.
    for _ in 0..4 {
        assert_eq!(result_of_write(&mut raw, CH1, offset::STREAM, &packet), 0);
    }
    assert_eq!(
        result_of_write(&mut raw, CH1, offset::STREAM, &packet),
        0x708
    );
    let (r, fill) = result_of_read(&mut raw, CH1, offset::STREAM_FILL, 8);
    assert_eq!(r, 0);
    assert_eq!(u32_at(&fill, 0), 3968);
    assert_eq!(u32_at(&fill, 4), 4094 - 3968);
    // Sizes.
    assert_eq!(result_of_write(&mut raw, CH1, offset::STREAM, b""), 0x705);
    assert_eq!(
        result_of_write(&mut raw, CH1, offset::STREAM, &[b'X'; 993]),
        0x705
    );
    // The newer index group reaches the same channel: 126 bytes free, 200 do not fit.
    let p200 = [vec![b'Y'; 198], b"\r\n".to_vec()].concat();
    assert_eq!(
        result_of_write(&mut raw, 0x120101, offset::STREAM, &p200),
        0x708
    );
    assert_eq!(
        result_of_write(&mut raw, 0x120101, offset::STREAM, b"N1\r\n"),
        0
    );
    // Reset deletes the buffer content.
    assert_eq!(result_of_write(&mut raw, CH1, offset::RESET, &[]), 0);
    assert_eq!(
        u32_at(&result_of_read(&mut raw, CH1, offset::STREAM_FILL, 8).1, 0),
        0
    );
    // A line without CR LF: 0x706, channel error 21476, state ERROR; what the buffer held
    // stays (the channel refuses the packet, it does not empty the buffer).
    assert_eq!(result_of_write(&mut raw, CH1, offset::STREAM, b"N5\r\n"), 0);
    assert_eq!(
        result_of_write(&mut raw, CH1, offset::STREAM, b"N10 X1\n"),
        0x706
    );
    assert_eq!(
        u32_at(&result_of_read(&mut raw, CH1, offset::STREAM_FILL, 8).1, 0),
        4
    );
    let (_, ms) = result_of_read(&mut raw, CH1, offset::MODE_STATE, 8);
    assert_eq!(u32_at(&ms, 4), 6);
    let (_, msg) = result_of_read(&mut raw, CH1, offset::ERROR_MESSAGE, 200);
    assert!(String::from_utf8_lossy(&msg).contains("21476"));
    // In ERROR nothing drains the buffer before a reset: a write is refused outright, 0x707,
    // not "busy" (retrying cannot succeed; docs/exactly-once.md).
    assert_eq!(
        result_of_write(&mut raw, CH1, offset::STREAM, b"N20 X2\r\n"),
        0x707
    );
    drop(raw);
    srv.shutdown();
    let events = channels.events();
    assert_eq!(
        refusals(&events, 11012),
        2,
        "each full write (0x708) is one refusal 11012 of the channel"
    );
}

#[test]
fn groups_offsets_and_sizes_are_checked() {
    let (srv, _b) = server();
    let mut raw = Raw::connect(srv.local_addr());
    assert_eq!(
        result_of_read(&mut raw, 0x20100, offset::MODE_STATE, 8).0,
        0x702,
        "channel 0"
    );
    assert_eq!(
        result_of_read(&mut raw, 0x20103, offset::MODE_STATE, 8).0,
        0x702,
        "channel 3 of 2"
    );
    assert_eq!(result_of_read(&mut raw, 0x4020, 0, 8).0, 0x702);
    assert_eq!(
        result_of_read(&mut raw, 0x20102, offset::MODE_STATE, 8).0,
        0,
        "channel 2 exists"
    );
    assert_eq!(result_of_read(&mut raw, CH1, 0x7777, 8).0, 0x703);
    assert_eq!(
        result_of_read(&mut raw, CH1, offset::MODE_STATE, 4).0,
        0x705
    );
    assert_eq!(
        result_of_read(&mut raw, CH1, offset::STREAM, 8).0,
        0x704,
        "write-only"
    );
    assert_eq!(
        result_of_write(&mut raw, CH1, offset::MODE_STATE, &[0; 8]),
        0x704,
        "read-only"
    );
    assert_eq!(result_of_write(&mut raw, CH1, 0x7777, &[0; 4]), 0x703);
    assert_eq!(
        result_of_write(&mut raw, CH1, offset::COMMAND_MODE, &[2, 0, 0]),
        0x705
    );
    assert_eq!(
        result_of_write(&mut raw, CH1, offset::COMMAND_MODE, &9i32.to_le_bytes()),
        0x706
    );
    assert_eq!(
        result_of_write(&mut raw, CH1, offset::HOLD, &[]),
        0,
        "hold while not active: accepted, nothing to hold"
    );
    assert_eq!(
        u32_at(&result_of_read(&mut raw, CH1, offset::MODE_STATE, 8).1, 4),
        3,
        "still READY"
    );
    assert_eq!(
        result_of_write(&mut raw, CH1, offset::FEED_OVERRIDE, &1500u16.to_le_bytes()),
        0
    );
    assert_eq!(
        result_of_write(&mut raw, CH1, offset::FEED_OVERRIDE, &2500u16.to_le_bytes()),
        0x706
    );
    assert_eq!(
        result_of_write(&mut raw, CH1, offset::FEED_OVERRIDE, &[1, 2, 3]),
        0x705
    );
    assert_eq!(
        result_of_write(&mut raw, CH1, offset::COMMAND_PROGRAM, &[0]),
        0x705,
        "empty name"
    );
}

#[test]
fn program_start_hold_resume_and_ve_variables() {
    let (srv, channels) = server();
    let mut raw = Raw::connect(srv.local_addr());
    assert_eq!(
        result_of_write(&mut raw, CH1, offset::COMMAND_MODE, &2i32.to_le_bytes()),
        0
    );
    assert_eq!(
        result_of_write(
            &mut raw,
            CH1,
            offset::COMMAND_PROGRAM,
            b"streaming.nc\0junk"
        ),
        0
    );
    assert_eq!(
        result_of_write(&mut raw, CH1, offset::COMMAND_STATE, &4i16.to_le_bytes()),
        0
    );
    let (_, ms) = result_of_read(&mut raw, CH1, offset::MODE_STATE, 8);
    assert_eq!((u32_at(&ms, 0), u32_at(&ms, 4)), (2, 4));
    assert_eq!(channels.status(1).program.as_deref(), Some("streaming.nc"));
    assert_eq!(result_of_write(&mut raw, CH1, offset::HOLD, &[1]), 0);
    assert_eq!(
        u32_at(&result_of_read(&mut raw, CH1, offset::MODE_STATE, 8).1, 4),
        5
    );
    assert_eq!(result_of_write(&mut raw, CH1, offset::RESUME, &[1]), 0);
    assert_eq!(
        u32_at(&result_of_read(&mut raw, CH1, offset::MODE_STATE, 8).1, 4),
        4
    );

    // V.E. variables live in the SDA task (port 552, decoder group 0x1223<ch>).
    let sda = AmsAddr {
        port: 552,
        ..device()
    };
    let mut sda_call = |command, invoke, data: &[u8]| {
        raw.send(&request_bytes(
            command,
            sda,
            client_addr(40000),
            invoke,
            data,
        ));
        raw.frame().1
    };
    let write_by_name = [b"V.E.speed\0".as_slice(), &12.5f64.to_le_bytes()].concat();
    let d = sda_call(WRITE, 1, &write_req(0x122301, 0x4A, &write_by_name));
    assert_eq!(u32_at(&d, 0), 0);
    let d = sda_call(
        READ_WRITE,
        2,
        &request::read_write(0x122301, 0x48, 8, b"V.E.SPEED\0"),
    );
    assert_eq!(u32_at(&d, 0), 0);
    assert_eq!(f64::from_le_bytes(d[8..16].try_into().unwrap()), 12.5);
    let d = sda_call(
        READ_WRITE,
        3,
        &request::read_write(0x122301, 0x48, 8, b"V.E.nope"),
    );
    assert_eq!(u32_at(&d, 0), 0x70C);
    assert_eq!(d.len(), 8);
    let d = sda_call(WRITE, 4, &write_req(0x122301, 0x4A, b"V.E.speed\0abc"));
    assert_eq!(u32_at(&d, 0), 0x705);

    // Streamed lines are executed while ACTIVE: block counter and positions move (12.8 mm
    // at F6000 take about 0.2 s). `#FLUSH` releases the move from the lookahead window, which
    // would otherwise wait for more blocks (README, Motion).
    assert_eq!(
        result_of_write(
            &mut raw,
            CH1,
            offset::STREAM,
            b"N10 G1 X12.5 Y-3 F6000\r\n#FLUSH\r\n"
        ),
        0
    );
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        let (_, c) = result_of_read(&mut raw, CH1, offset::BLOCK_COUNTER, 8);
        let (_, p) = result_of_read(&mut raw, CH1, offset::POSITIONS, 24);
        let x = f64::from_le_bytes(p[0..8].try_into().unwrap());
        let y = f64::from_le_bytes(p[8..16].try_into().unwrap());
        let blocks = u64::from_le_bytes(c[..8].try_into().unwrap());
        // The counter is read before the positions: once it counts both blocks (the move and
        // #FLUSH) and the axes stand at the target, the line was executed exactly once.
        if blocks >= 2 && (x - 12.5).abs() < 1e-9 && (y + 3.0).abs() < 1e-9 {
            assert_eq!(blocks, 2);
            break;
        }
        assert!(Instant::now() < deadline, "line never executed: ({x}, {y})");
        std::thread::sleep(Duration::from_millis(2));
    }
}

#[test]
fn notifications_arrive_on_change_and_stop_after_delete() {
    let (srv, _b) = server();
    let mut raw = Raw::connect(srv.local_addr());
    // On change (4), cycle 1 ms in 100 ns units.
    let add = request::add_notification(CH1, offset::MODE_STATE, 8, 4, 0, 10_000);
    let (h, d) = raw.call(ADD_NOTIFICATION, 1, &add);
    assert_eq!(h.invoke_id, 1);
    assert_eq!(d.len(), 8);
    assert_eq!(u32_at(&d, 0), 0);
    let handle = u32_at(&d, 4);

    // The first sample is the current value.
    let (nh, nd) = raw.frame();
    assert_eq!(nh.command.to_u16(), 8);
    assert_eq!(nh.target, client_addr(40000), "sent to the requester");
    assert_eq!(nh.source, device(), "from the device it addressed");
    let samples = payload::decode_notification(&nd).unwrap();
    assert_eq!(samples.len(), 1);
    assert_eq!(samples[0].handle, handle);
    assert_eq!(
        samples[0].data,
        [2, 0, 0, 0, 3, 0, 0, 0],
        "AUTOMATIC / READY"
    );

    // No change, no sample.
    assert!(raw.frame_bytes(Duration::from_millis(50)).is_none());

    // A mode change produces one.
    raw.send(&request_bytes(
        WRITE,
        device(),
        client_addr(40000),
        2,
        &write_req(CH1, offset::COMMAND_MODE, &1i32.to_le_bytes()),
    ));
    let mut got_response = false;
    let mut got_sample = false;
    for _ in 0..2 {
        let (h, d) = raw.frame();
        match h.command.to_u16() {
            3 => got_response = true,
            8 => {
                let s = payload::decode_notification(&d).unwrap();
                assert_eq!(s[0].data, [1, 0, 0, 0, 3, 0, 0, 0], "STANDBY / READY");
                got_sample = true;
            }
            c => panic!("unexpected command {c}"),
        }
    }
    assert!(got_response && got_sample);

    let (_, d) = raw.call(DEL_NOTIFICATION, 3, &handle.to_le_bytes());
    assert_eq!(d, [0, 0, 0, 0]);
    let (_, d) = raw.call(DEL_NOTIFICATION, 4, &handle.to_le_bytes());
    assert_eq!(d, 0x714u32.to_le_bytes(), "second delete: invalid handle");
    raw.call(
        WRITE,
        5,
        &write_req(CH1, offset::COMMAND_MODE, &2i32.to_le_bytes()),
    );
    assert!(
        raw.frame_bytes(Duration::from_millis(50)).is_none(),
        "sample after delete"
    );
}

#[test]
fn notifications_on_unreadable_objects_are_refused_and_handles_are_bounded() {
    let cfg = ServerConfig {
        max_notifications: 2,
        ..ServerConfig::default()
    };
    let (srv, _b) = server_with(cfg);
    let mut raw = Raw::connect(srv.local_addr());
    let bad = request::add_notification(CH1, offset::STREAM, 8, 4, 0, 10_000);
    assert_eq!(
        raw.call(ADD_NOTIFICATION, 1, &bad).1,
        [0x04, 0x07, 0, 0, 0, 0, 0, 0]
    );
    // Cyclic (3) at 10 ms, on the block counter.
    let ok = request::add_notification(CH1, offset::BLOCK_COUNTER, 8, 3, 0, 100_000);
    let mut handles = Vec::new();
    let mut invoke = 2;
    let mut results = Vec::new();
    while results.len() < 3 {
        raw.send(&request_bytes(
            ADD_NOTIFICATION,
            device(),
            client_addr(40000),
            invoke,
            &ok,
        ));
        loop {
            let (h, d) = raw.frame();
            if h.command.to_u16() == 6 {
                results.push(u32_at(&d, 0));
                handles.push(u32_at(&d, 4));
                break;
            }
        }
        invoke += 1;
    }
    assert_eq!(results, [0, 0, 0x716]);
    // Cyclic samples keep coming although nothing changes.
    let mut samples = 0;
    let deadline = Instant::now() + Duration::from_secs(30);
    while samples < 6 && Instant::now() < deadline {
        if let Some(f) = raw.frame_bytes(Duration::from_millis(200)) {
            if f[22] == 8 {
                samples += 1;
            }
        }
    }
    assert!(samples >= 6, "cyclic notifications: {samples}");
}

#[test]
fn unlisted_net_ids_get_no_service_and_listed_ones_do() {
    let cfg = ServerConfig {
        allow: vec!["10.1.2.3.1.1".parse::<RouteEntry>().unwrap()],
        ..ServerConfig::default()
    };
    let (srv, _b) = server_with(cfg);
    let mut raw = Raw::connect(srv.local_addr());
    let stranger = AmsAddr {
        net_id: "9.9.9.9.1.1".parse().unwrap(),
        port: 40000,
    };
    raw.send(&request_bytes(READ_STATE, device(), stranger, 1, &[]));
    assert!(
        raw.frame_bytes(Duration::from_millis(200)).is_none(),
        "unrouted frame answered"
    );
    assert_eq!(
        raw.call(READ_STATE, 2, &[]).0.invoke_id,
        2,
        "routed NetId served"
    );
}

#[test]
fn unlisted_ip_addresses_are_disconnected() {
    let cfg = ServerConfig {
        allow: vec!["10.9.9.9".parse::<RouteEntry>().unwrap()],
        ..ServerConfig::default()
    };
    let (srv, _b) = server_with(cfg);
    let mut raw = Raw::connect(srv.local_addr());
    raw.send(&request_bytes(READ_STATE, device(), client_addr(1), 1, &[]));
    assert!(raw.closed_within(Duration::from_secs(10)));

    let cfg = ServerConfig {
        allow: vec!["127.0.0.1".parse::<RouteEntry>().unwrap()],
        ..ServerConfig::default()
    };
    let (srv, _b) = server_with(cfg);
    let mut raw = Raw::connect(srv.local_addr());
    assert_eq!(raw.call(READ_STATE, 3, &[]).0.invoke_id, 3);
}

#[test]
fn non_loopback_bind_needs_the_opt_in() {
    let channels = Channels::start(1);
    let backend = std::sync::Arc::clone(&channels.backend);
    let cfg = ServerConfig {
        bind: "0.0.0.0:0".parse().unwrap(),
        ..ServerConfig::default()
    };
    let err = ncchannel::ads::spawn(cfg.clone(), backend.clone())
        .err()
        .expect("refused");
    assert_eq!(err.kind(), std::io::ErrorKind::PermissionDenied);
    let srv = ncchannel::ads::spawn(
        ServerConfig {
            allow_non_loopback: true,
            ..cfg
        },
        backend,
    )
    .unwrap();
    let port = srv.local_addr().port();
    let mut raw = Raw::connect(format!("127.0.0.1:{port}").parse().unwrap());
    assert_eq!(raw.call(READ_STATE, 1, &[]).0.invoke_id, 1);
    srv.shutdown();
}

#[test]
fn shutdown_closes_connections() {
    let (srv, _b) = server();
    let mut raw = Raw::connect(srv.local_addr());
    raw.call(READ_STATE, 1, &[]);
    srv.shutdown();
    assert!(raw.closed_within(Duration::from_secs(10)));
}

#[test]
fn router_port_connect_hands_out_an_address() {
    let (srv, _b) = server();
    let mut raw = Raw::connect(srv.local_addr());
    raw.send(&[0x00, 0x10, 2, 0, 0, 0, 0, 0]);
    let reply = raw.frame_bytes(Duration::from_secs(10)).unwrap();
    assert_eq!(&reply[..6], &[0x00, 0x10, 8, 0, 0, 0]);
    assert_eq!(&reply[6..12], &[127, 0, 0, 1, 1, 1]);
    assert!(u16::from_le_bytes([reply[12], reply[13]]) >= 32768);
}

/// AddDeviceNotification result of one request on `raw` (skipping samples in between).
fn add_result(raw: &mut Raw, invoke: u32, add: &[u8]) -> u32 {
    raw.send(&request_bytes(
        ADD_NOTIFICATION,
        device(),
        client_addr(40000),
        invoke,
        add,
    ));
    loop {
        let (h, d) = raw.frame();
        if h.command.to_u16() == ADD_NOTIFICATION && h.invoke_id == invoke {
            return u32_at(&d, 0);
        }
    }
}

#[test]
fn one_connection_spending_its_sample_budget_leaves_the_others_theirs() {
    let (srv, _b) = server();
    let mut greedy = Raw::connect(srv.local_addr());
    // Cyclic at 1 ms: 1000 samples a second each; ten fill one connection's budget.
    let one_ms = request::add_notification(CH1, offset::BLOCK_COUNTER, 8, 3, 0, 10_000);
    let results: Vec<u32> = (1..=11)
        .map(|i| add_result(&mut greedy, i, &one_ms))
        .collect();
    assert_eq!(results[..10], [0; 10], "ten 1 ms handles on one connection");
    assert_eq!(results[10], 0x716, "the eleventh is beyond its own budget");
    // Another client still gets a 100 ms handle and 1 ms handles of its own.
    let mut other = Raw::connect(srv.local_addr());
    let slow = request::add_notification(CH1, offset::MODE_STATE, 8, 4, 0, 1_000_000);
    assert_eq!(add_result(&mut other, 1, &slow), 0);
    assert_eq!(add_result(&mut other, 2, &one_ms), 0);
    assert_eq!(add_result(&mut other, 3, &one_ms), 0);
}

/// The real machine with one tick, asked for by the test, that overruns by `STALL`: the shape
/// of a tick doing work that grows with its input. It says on `began` when the stall starts.
struct StallWhenAsked {
    machine: ncchannel::machine::Machine,
    ask: std::sync::Arc<std::sync::atomic::AtomicBool>,
    began: crossbeam_channel::Sender<()>,
}

const STALL: Duration = Duration::from_secs(4);

impl ncchannel::runtime::Cycle for StallWhenAsked {
    type Request = ncchannel::machine::Request;

    fn serve(&mut self, req: Self::Request, tick: &ncchannel::runtime::Tick) {
        self.machine.serve(req, tick);
    }

    fn step(&mut self, tick: &ncchannel::runtime::Tick) -> ncchannel::runtime::Flow {
        if self.ask.swap(false, std::sync::atomic::Ordering::SeqCst) {
            let _ = self.began.send(());
            std::thread::sleep(STALL);
        }
        self.machine.step(tick)
    }
}

#[test]
fn fifty_requests_in_flight_through_a_stall_are_each_answered_busy_within_the_reply_timeout() {
    requests_in_flight_through_a_stall(false);
}

/// The same, with the 49 behind the first sent while it already waits on the stalled runtime:
/// they are read (and stamped) while it waits, not when it is answered.
#[test]
fn requests_sent_behind_one_waiting_on_a_stall_are_stamped_as_they_arrive() {
    requests_in_flight_through_a_stall(true);
}

/// 50 stream writes in flight through a 4 s stall; `first_alone`: the first is sent 20 ms
/// before the other 49.
fn requests_in_flight_through_a_stall(first_alone: bool) {
    use ncchannel::machine::{Machine, StopWhen};
    use ncchannel::report::event::EventLog;
    use ncchannel::runtime::{Clock, Runtime};
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;

    let params = crate::support::ads::Params::new(1);
    let config = ncchannel::params::load(&params.startup()).unwrap();
    let channels = ncchannel::channels(&config, true, &ncchannel::Loader::start()).unwrap();
    let ask = Arc::new(AtomicBool::new(false));
    let (began_tx, began) = crossbeam_channel::bounded(1);
    let cycle = StallWhenAsked {
        machine: Machine::new(channels, EventLog::disabled(), StopWhen::Never),
        ask: Arc::clone(&ask),
        began: began_tx,
    };
    let period = Duration::from_micros(config.runtime.cycle_period_us);
    let (mut rt, tx) = Runtime::new(cycle, period, Clock::RealTime);
    let stop = rt.stop_handle();
    let runtime = std::thread::spawn(move || rt.run(None));
    // As `serve` builds it: the default reply timeout (500 ms); 1 s when the first is sent
    // alone, so an answer counted from when the first was answered (about 2 s) stands apart
    // from one counted from its own arrival (about 1 s).
    let backend = ncchannel::machine::remote::ChannelBackend::new(tx, 1);
    let backend = if first_alone {
        backend.with_reply_timeout(Duration::from_secs(1))
    } else {
        backend
    };
    let srv = ncchannel::ads::spawn(
        ServerConfig {
            bind: "127.0.0.1:0".parse().unwrap(),
            ..ServerConfig::default()
        },
        Arc::new(backend),
    )
    .unwrap();
    let mut raw = Raw::connect(srv.local_addr());
    let line = b"N1\r\n";
    let write = write_req(CH1, offset::STREAM, line);
    assert_eq!(
        raw.call(WRITE, 1, &write).1,
        [0; 4],
        "one line before the stall"
    );
    let (_, d) = raw.call(READ, 2, &request::read(CH1, offset::STREAM_FILL, 8));
    let before = u32_at(&d, 4);

    ask.store(true, Ordering::SeqCst);
    began
        .recv_timeout(Duration::from_secs(10))
        .expect("the runtime stalls");
    // 50 writes in flight at once, as an HMI's concurrent requests.
    let n = 50;
    let burst: Vec<u8> = (0..n)
        .flat_map(|i| request_bytes(WRITE, device(), client_addr(40000), 100 + i, &write))
        .collect();
    let sent = Instant::now();
    if first_alone {
        let first = request_bytes(WRITE, device(), client_addr(40000), 100, &write).len();
        raw.send(&burst[..first]);
        std::thread::sleep(Duration::from_millis(20));
        raw.send(&burst[first..]);
    } else {
        raw.send(&burst);
    }
    let mut answers = Vec::new();
    while answers.len() < n as usize {
        let (h, d) = raw.frame();
        if h.command.to_u16() == WRITE {
            answers.push((h.invoke_id, u32_at(&d, 0), sent.elapsed()));
        }
    }
    let slowest = answers.iter().map(|a| a.2).max().unwrap();
    println!("STALL 50 in flight: slowest answer after {slowest:?}");
    assert!(
        answers.iter().all(|a| a.1 == 0x708),
        "every write in the stall answered busy: {answers:?}"
    );
    // Each within the reply timeout of its arrival (500 ms) plus scheduling slack, far below
    // ads-client's 2000 ms; one after another 50 ms apart the last took 2950 ms. Sent behind
    // the first (1 s timeout): about 1.05 s; read only once the first is answered, 2 s.
    let bound = Duration::from_millis(if first_alone { 1600 } else { 1500 });
    assert!(slowest < bound, "slowest answer {slowest:?}: {answers:?}");
    let ids: std::collections::BTreeSet<u32> = answers.iter().map(|a| a.0).collect();
    assert_eq!(ids.len(), n as usize, "each request answered once");

    // After the stall: none of the 50 was applied, the next write is.
    let mut invoke = 1000;
    let fill = loop {
        invoke += 1;
        assert!(
            invoke < 10_000,
            "the runtime never answered after the stall"
        );
        let (_, d) = raw.call(READ, invoke, &request::read(CH1, offset::STREAM_FILL, 8));
        if u32_at(&d, 0) == 0 {
            break u32_at(&d, 4);
        }
    };
    assert_eq!(fill, before, "none of the writes answered busy was applied");
    assert_eq!(raw.call(WRITE, invoke + 1, &write).1, [0; 4]);
    drop(raw);
    srv.shutdown();
    stop.stop();
    runtime.join().unwrap();
}

/// `cnc_tick_counter_r` (docs/ads.md): the tick index, one more every tick.
const TICK_COUNTER: u32 = 0x251;

#[test]
fn a_1_ms_notification_sees_every_tick_and_a_cyclic_one_samples_every_cycle() {
    let (srv, _b) = server();
    let mut raw = Raw::connect(srv.local_addr());
    // On change (4) checked every 1 ms, and cyclic (3) every 10 ms, on a value that changes
    // every tick of the 1 ms cycle.
    let on_change = request::add_notification(CH1, TICK_COUNTER, 4, 4, 0, 10_000);
    let cyclic = request::add_notification(CH1, TICK_COUNTER, 4, 3, 0, 100_000);
    let every = u32_at(&raw.call(ADD_NOTIFICATION, 1, &on_change).1, 4);
    let mut tens = None;
    let mut seen: std::collections::HashMap<u32, Vec<u32>> = Default::default();
    raw.send(&request_bytes(
        ADD_NOTIFICATION,
        device(),
        client_addr(40000),
        2,
        &cyclic,
    ));
    while seen.get(&every).map_or(0, Vec::len) < 1000
        || tens.is_none_or(|t| seen.get(&t).map_or(0, Vec::len) < 50)
    {
        let (h, d) = raw.frame();
        match h.command.to_u16() {
            ADD_NOTIFICATION => tens = Some(u32_at(&d, 4)),
            8 => {
                for s in payload::decode_notification(&d).unwrap() {
                    seen.entry(s.handle).or_default().push(u32_at(&s.data, 0));
                }
            }
            _ => {}
        }
    }
    let steps = |h: u32| -> Vec<u32> { seen[&h].windows(2).map(|w| w[1] - w[0]).collect() };
    assert!(
        steps(every).iter().all(|&d| d == 1),
        "the 1 ms on-change handle saw every tick: {:?}",
        steps(every)
    );
    let tens = tens.unwrap();
    assert!(
        steps(tens).iter().all(|&d| d == 10),
        "the 10 ms cyclic handle sampled every 10th tick: {:?}",
        steps(tens)
    );
}

/// GEO's position-controller tick counter (port 551, group 0x120300, element 0x07).
const GEO_TICK_COUNTER: (u32, u32) = (0x12_0300, 0x07);

/// Send `data` as `command` to `port` of the device and return the response's data.
fn call_port(raw: &mut Raw, port: u16, command: u16, invoke: u32, data: &[u8]) -> Vec<u8> {
    let target = AmsAddr { port, ..device() };
    raw.send(&request_bytes(
        command,
        target,
        client_addr(40000),
        invoke,
        data,
    ));
    loop {
        let (h, d) = raw.frame();
        if h.invoke_id == invoke && h.command.to_u16() == command {
            return d;
        }
    }
}

#[test]
fn notifications_on_geo_hli_and_sda_objects_are_evaluated_in_the_cycle() {
    let (srv, _b) = server();
    let mut raw = Raw::connect(srv.local_addr());
    // An HLI symbol by handle (port 851) and an SDA zero offset by handle (port 552): cyclic
    // every 1 ms. GEO's tick counter (port 551): on change every 1 ms.
    let state_r = b"HLI_Global_Variables.gpCh[0]^.channel_mc_control.mode_and_state.state_r\0";
    let d = call_port(
        &mut raw,
        851,
        READ_WRITE,
        1,
        &request::read_write(0xF003, 0, 4, state_r),
    );
    assert_eq!(u32_at(&d, 0), 0, "handle of state_r");
    let hli_handle = u32_at(&d, 8);
    let d = call_port(
        &mut raw,
        552,
        READ_WRITE,
        2,
        &request::read_write(0x12_2301, 0x46, 4, b"V.G.NP[1].V"),
    );
    assert_eq!(u32_at(&d, 0), 0, "handle of V.G.NP[1].V");
    let sda_handle = u32_at(&d, 8);
    let (geo, hli, sda) = (
        u32_at(
            &call_port(
                &mut raw,
                551,
                ADD_NOTIFICATION,
                3,
                &request::add_notification(GEO_TICK_COUNTER.0, GEO_TICK_COUNTER.1, 4, 4, 0, 10_000),
            ),
            4,
        ),
        u32_at(
            &call_port(
                &mut raw,
                851,
                ADD_NOTIFICATION,
                4,
                &request::add_notification(0xF005, hli_handle, 8, 3, 0, 10_000),
            ),
            4,
        ),
        u32_at(
            &call_port(
                &mut raw,
                552,
                ADD_NOTIFICATION,
                5,
                &request::add_notification(0x12_2301, sda_handle, 12, 3, 0, 10_000),
            ),
            4,
        ),
    );
    // Samples in the order they arrive: every due watch of a tick is evaluated in that tick,
    // in the order the handles were added, and queued in order.
    let mut order = Vec::new();
    while order.iter().filter(|(h, _)| *h == geo).count() < 500 {
        let (h, d) = raw.frame();
        if h.command.to_u16() == 8 {
            for s in payload::decode_notification(&d).unwrap() {
                order.push((s.handle, s.data));
            }
        }
    }
    let ticks: Vec<u32> = order
        .iter()
        .filter(|(h, _)| *h == geo)
        .map(|(_, d)| u32_at(d, 0))
        .collect();
    assert!(
        ticks.windows(2).all(|w| w[1] == w[0] + 1),
        "the 1 ms on-change GEO handle saw every tick: {ticks:?}"
    );
    // Once all three sample, each tick gives one sample of each, GEO's first.
    let first_sda = order.iter().position(|(h, _)| *h == sda).unwrap();
    let start = first_sda
        + order[first_sda..]
            .iter()
            .position(|(h, _)| *h == geo)
            .unwrap();
    let settled: Vec<u32> = order[start..].iter().map(|(h, _)| *h).collect();
    for tick in settled.chunks_exact(3) {
        assert_eq!(
            tick,
            [geo, hli, sda],
            "one sample of each per tick: {settled:?}"
        );
    }
    let (hli_bytes, sda_bytes) = (
        &order.iter().find(|(h, _)| *h == hli).unwrap().1,
        &order.iter().find(|(h, _)| *h == sda).unwrap().1,
    );
    assert_eq!(hli_bytes.len(), 8, "state_r: mode and state");
    assert_eq!(sda_bytes.len(), 12, "V.G.NP[1].V: one DINT per axis");
}
