//! The TwinCAT runtime services on the wire: the system service on AMS port 10000, the PLC's
//! symbol and data-type uploads on 851 byte for byte (docs/ads.md), and ADS sum commands on
//! every port, malformed ones included, against real channels behind the server.

use crate::support::ads::*;
use ncchannel::ads::frame::AmsAddr;
use ncchannel::ads::objects::{offset, GROUP_CHANNEL_NEW};
use ncchannel::ads::payload::request;

const READ_DEVICE_INFO: u16 = 1;
const READ: u16 = 2;
const READ_STATE: u16 = 4;
const READ_WRITE: u16 = 9;
const SUM_READ: u32 = 0xF080;
const SUM_WRITE: u32 = 0xF081;
const SUM_READ_WRITE: u32 = 0xF082;
const STATE_R: &str = "HLI_Global_Variables.gpCh[0]^.channel_mc_control.mode_and_state.state_r";

fn at(port: u16) -> AmsAddr {
    AmsAddr { port, ..device() }
}

/// One request to `port`; the response's payload (the AMS header error must be 0).
fn call(raw: &mut Raw, port: u16, command: u16, data: &[u8]) -> Vec<u8> {
    raw.send(&request_bytes(
        command,
        at(port),
        client_addr(40000),
        9,
        data,
    ));
    let (h, payload) = raw.frame();
    assert_eq!(h.error, 0, "AMS error for port {port}");
    payload
}

fn words(w: &[u32]) -> Vec<u8> {
    w.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// A ReadWrite's result and data.
fn read_write(
    raw: &mut Raw,
    port: u16,
    group: u32,
    off: u32,
    len: u32,
    data: &[u8],
) -> (u32, Vec<u8>) {
    let r = call(
        raw,
        port,
        READ_WRITE,
        &request::read_write(group, off, len, data),
    );
    (u32_at(&r, 0), r[8..].to_vec())
}

fn read(raw: &mut Raw, port: u16, group: u32, off: u32, len: u32) -> (u32, Vec<u8>) {
    let r = call(raw, port, READ, &read_req(group, off, len));
    (u32_at(&r, 0), r[8..].to_vec())
}

fn u16_at(b: &[u8], at: usize) -> usize {
    usize::from(u16::from_le_bytes([b[at], b[at + 1]]))
}

fn text(b: &[u8], at: usize, n: usize) -> String {
    assert_eq!(b[at + n], 0, "NUL-terminated");
    String::from_utf8(b[at..at + n].to_vec()).unwrap()
}

#[test]
fn the_system_service_on_10000_is_in_run_and_names_itself() {
    let (srv, _b) = server();
    let mut raw = Raw::connect(srv.local_addr());
    assert_eq!(
        call(&mut raw, 10000, READ_STATE, &[]),
        [0, 0, 0, 0, 5, 0, 0, 0]
    );
    let info = call(&mut raw, 10000, READ_DEVICE_INFO, &[]);
    assert_eq!(u32_at(&info, 0), 0);
    assert_eq!(&info[8..22], b"TwinCAT System");
    let (r, ext) = read(&mut raw, 10000, 0xF0, 0, 16);
    assert_eq!((r, ext.len()), (0, 16), "the extended state");
    assert_eq!(
        &ext[0..6],
        &[5, 0, 0, 0, 0, 0],
        "RUN, device state 0, no restart"
    );
    assert_eq!(
        read(&mut raw, 10000, 0xF1, 0, 16).0,
        0x702,
        "no other objects"
    );
    let plc = call(&mut raw, 851, READ_DEVICE_INFO, &[]);
    assert_eq!(&plc[8..17], b"Plc30 App");
    // The PLC runtime's device data: ADS state RUN, device state 0.
    assert_eq!(read(&mut raw, 851, 0xF100, 0, 4), (0, vec![5, 0, 0, 0]));
    assert_eq!(
        read(&mut raw, 851, 0xF008, 0, 1),
        (0, vec![1]),
        "symbol version"
    );
}

#[test]
fn symbol_upload_lists_root_variables_with_value_by_handle_addresses() {
    let (srv, _b) = server();
    let mut raw = Raw::connect(srv.local_addr());
    let (r, info) = read(&mut raw, 851, 0xF00F, 0, 24);
    assert_eq!((r, info.len()), (0, 24));
    let (count, bytes) = (u32_at(&info, 0), u32_at(&info, 4));
    assert_eq!(
        read(&mut raw, 851, 0xF00C, 0, 8).1,
        info[..8],
        "upload info 1 agrees"
    );
    let (r, up) = read(&mut raw, 851, 0xF00B, 0, bytes);
    assert_eq!((r, up.len() as u32), (0, bytes));
    let (mut pos, mut seen) = (0, Vec::new());
    while pos < up.len() {
        let e = &up[pos..pos + u32_at(&up, pos) as usize];
        let (group, handle, size) = (u32_at(e, 4), u32_at(e, 8), u32_at(e, 12));
        let (nl, tl, cl) = (u16_at(e, 24), u16_at(e, 26), u16_at(e, 28));
        assert_eq!(
            e.len(),
            30 + nl + tl + cl + 3,
            "entry length covers the texts"
        );
        let name = text(e, 30, nl);
        let ty = text(e, 31 + nl, tl);
        assert_eq!(group, 0xF005);
        // The address reads the symbol's bytes.
        let (r, v) = read(&mut raw, 851, group, handle, size);
        assert_eq!((r, v.len() as u32), (0, size), "{name}");
        if name == STATE_R {
            assert_eq!((ty.as_str(), size), ("HLI_IMCM_MODE_STATE", 8));
            assert_eq!(v, [2, 0, 0, 0, 3, 0, 0, 0], "AUTOMATIC / READY");
            assert_eq!(u32_at(e, 20) & 0x20, 0x20, "read-only flag");
        }
        seen.push(name);
        pos += e.len();
    }
    assert_eq!(seen.len() as u32, count);
    assert!(seen.iter().any(|n| n == STATE_R));
    assert!(
        !seen.iter().any(|n| n.ends_with(".state_r.mode")),
        "members are in the types"
    );
    assert_eq!(
        read(&mut raw, 851, 0xF00B, 0, bytes - 1).0,
        0x705,
        "too short a buffer"
    );
}

#[test]
fn data_types_describe_the_hli_structs_member_by_member() {
    let (srv, _b) = server();
    let mut raw = Raw::connect(srv.local_addr());
    let (r, e) = read_write(&mut raw, 851, 0xF011, 0, u32::MAX, b"HLI_IMCM_MODE_STATE\0");
    assert_eq!(r, 0);
    assert_eq!(u32_at(&e, 0) as usize, e.len());
    assert_eq!(
        (u32_at(&e, 16), u32_at(&e, 24)),
        (8, 65),
        "8 bytes, ADST_BIGTYPE"
    );
    let (nl, tl, cl, dims, items) = (
        u16_at(&e, 32),
        u16_at(&e, 34),
        u16_at(&e, 36),
        u16_at(&e, 38),
        u16_at(&e, 40),
    );
    assert_eq!((dims, items), (0, 2));
    assert_eq!(text(&e, 42, nl), "HLI_IMCM_MODE_STATE");
    let mut pos = 42 + nl + tl + cl + 3;
    for (name, offset_bytes) in [("mode", 0), ("state", 4)] {
        let item = &e[pos..pos + u32_at(&e, pos) as usize];
        assert_eq!(
            (u32_at(item, 16), u32_at(item, 20), u32_at(item, 24)),
            (4, offset_bytes, 19)
        );
        let nl = u16_at(item, 32);
        assert_eq!(text(item, 42, nl), name);
        assert_eq!(text(item, 43 + nl, u16_at(item, 34)), "UDINT");
        pos += item.len();
    }
    assert_eq!(pos, e.len());
    let (r, a) = read_write(
        &mut raw,
        851,
        0xF011,
        0,
        u32::MAX,
        b"ARRAY [0..19] OF TECHNO_UNIT_CH\0",
    );
    assert_eq!(r, 0);
    assert_eq!(
        (u32_at(&a, 16), u16_at(&a, 38)),
        (940, 1),
        "20 x 47 bytes, one dimension"
    );
    assert_eq!(
        read_write(&mut raw, 851, 0xF011, 0, u32::MAX, b"NOPE\0").0,
        0x710
    );
    let (_, info) = read(&mut raw, 851, 0xF00F, 0, 24);
    let (r, types) = read(&mut raw, 851, 0xF00E, 0, u32_at(&info, 12));
    assert_eq!((r, types.len() as u32), (0, u32_at(&info, 12)));
}

#[test]
fn a_sum_read_answers_every_sub_request_with_its_own_result() {
    let (srv, _b) = server();
    let mut raw = Raw::connect(srv.local_addr());
    let ch = GROUP_CHANNEL_NEW + 1;
    let subs = words(&[
        ch,
        offset::MODE_STATE,
        8,
        ch,
        0xFFFF_FF00,
        4,
        ch,
        offset::BLOCK_COUNT,
        4,
    ]);
    let (r, reply) = read_write(&mut raw, 553, SUM_READ, 3, 12 + 16, &subs);
    assert_eq!(r, 0);
    assert_eq!(reply.len(), 12 + 16);
    assert_eq!(u32_at(&reply, 0), 0);
    assert_ne!(u32_at(&reply, 4), 0, "unknown offset fails alone");
    assert_eq!(u32_at(&reply, 8), 0);
    assert_eq!(
        &reply[12..20],
        &words(&[2, 3])[..],
        "AUTOMATIC / READY in its slot"
    );
    assert_eq!(&reply[20..24], &[0; 4], "the failed slot is zeros");
    // Handles by sum read-write (0xF003 sub-requests), released by sum write (0xF006).
    let name = format!("{STATE_R}\0");
    let mut req = words(&[0xF003, 0, 4, name.len() as u32, 0xF003, 0, 4, 5]);
    req.extend(name.as_bytes());
    req.extend(b"nope\0");
    let (r, reply) = read_write(&mut raw, 851, SUM_READ_WRITE, 2, 1024, &req);
    assert_eq!(r, 0);
    assert_eq!(&reply[..16], &words(&[0, 4, 0x710, 0])[..]);
    let handle = u32_at(&reply, 16);
    assert_eq!(
        read(&mut raw, 851, 0xF005, handle, 8).1,
        [2, 0, 0, 0, 3, 0, 0, 0]
    );
    let mut req = words(&[0xF006, 0, 4]);
    req.extend(handle.to_le_bytes());
    assert_eq!(
        read_write(&mut raw, 851, SUM_WRITE, 1, 4, &req),
        (0, words(&[0]))
    );
}

#[test]
fn malformed_sum_commands_are_one_clear_error_and_the_connection_lives() {
    let (srv, _b) = server();
    let mut raw = Raw::connect(srv.local_addr());
    let ch = GROUP_CHANNEL_NEW + 1;
    let one = words(&[ch, offset::MODE_STATE, 8]);
    for (group, count, len, data, want, why) in [
        (SUM_READ, 0, 100, one.clone(), 0x706, "no sub-request"),
        (SUM_READ, 501, 100, one.clone(), 0x706, "more than 500"),
        (
            SUM_READ,
            u32::MAX,
            100,
            one.clone(),
            0x706,
            "a count from nowhere",
        ),
        (
            SUM_READ,
            2,
            100,
            one.clone(),
            0x705,
            "fewer heads than the count",
        ),
        (
            SUM_READ,
            1,
            11,
            one.clone(),
            0x705,
            "reply beyond the client's buffer",
        ),
        (
            SUM_READ,
            1,
            100,
            words(&[ch, 0, u32::MAX]),
            0x705,
            "a 4 GiB sub-read",
        ),
        (
            SUM_WRITE,
            1,
            4,
            words(&[ch, offset::FEED_OVERRIDE, 2]),
            0x705,
            "data missing",
        ),
        (
            SUM_READ_WRITE,
            1,
            100,
            words(&[ch, 0, 4, 9]),
            0x705,
            "write data missing",
        ),
        (
            0xF085,
            1,
            100,
            one.clone(),
            0x705,
            "sum add notification without a 40-byte entry",
        ),
    ] {
        assert_eq!(
            read_write(&mut raw, 553, group, count, len, &data).0,
            want,
            "{why}"
        );
    }
    // A sum command inside a sum command is refused per sub-request.
    let nested = words(&[SUM_READ, 1, 4]);
    let (r, reply) = read_write(&mut raw, 553, SUM_READ, 1, 8, &nested);
    assert_eq!((r, u32_at(&reply, 0)), (0, 0x702));
    assert_eq!(
        call(&mut raw, 553, READ_STATE, &[]),
        [0, 0, 0, 0, 5, 0, 0, 0]
    );
}
