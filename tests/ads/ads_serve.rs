//! End to end: the real channels in real time at 1 ms behind the ADS server, driven by
//! the independent `ads` crate client exactly as a streaming client drives a real controller.

use crate::support as common;
use crate::support::ads as ads_common;

use std::time::{Duration, Instant};

use ads::notif::{Attributes, TransmissionMode};
use ads::{AmsAddr, AmsNetId, Client, Source, Timeouts};
use ads_common::{Params, Served};
use ncchannel::ads::objects::offset;

const CH1: u32 = 0x20101;

fn connect(srv: &ncchannel::ads::ServerHandle) -> Client {
    let source = AmsAddr::new(AmsNetId::new(10, 1, 2, 3, 1, 1), 40100);
    Client::new(
        srv.local_addr(),
        Timeouts::new(Duration::from_secs(5)),
        Source::Addr(source),
    )
    .unwrap()
}

fn target() -> AmsAddr {
    AmsAddr::new(AmsNetId::new(127, 0, 0, 1, 1, 1), 553)
}

fn mode_state(dev: &ads::Device) -> (i32, i32) {
    let mut b = [0u8; 8];
    dev.read_exact(CH1, offset::MODE_STATE, &mut b).unwrap();
    (
        i32::from_le_bytes(b[0..4].try_into().unwrap()),
        i32::from_le_bytes(b[4..8].try_into().unwrap()),
    )
}

/// Whole lines, CR LF, packets of at most 992 bytes.
fn packets(lines: &[String]) -> Vec<Vec<u8>> {
    let mut out = vec![];
    let mut cur = Vec::new();
    for l in lines {
        let l = format!("{l}\r\n");
        if cur.len() + l.len() > 992 {
            out.push(std::mem::take(&mut cur));
        }
        cur.extend_from_slice(l.as_bytes());
    }
    out.push(cur);
    out
}

#[test]
fn ads_client_streams_5000_lines_into_a_running_channel_exactly_once_in_order() {
    let served = Served::start(Params::new(1));
    let client = connect(&served.server);
    let dev = client.device(target());

    // Notifications on mode/state changes, as an HMI watches the channel.
    let (handle, notes) = {
        let attr = Attributes::new(
            8,
            TransmissionMode::ServerOnChange,
            Duration::from_millis(1),
            Duration::from_millis(1),
        );
        (
            dev.add_notification(CH1, offset::MODE_STATE, &attr)
                .unwrap(),
            client.get_notification_channel(),
        )
    };

    // Start the streaming program: AUTOMATIC, program name, ACTIVE.
    dev.write_value(CH1, offset::COMMAND_MODE, &2i32).unwrap();
    dev.write(CH1, offset::COMMAND_PROGRAM, b"streaming.nc\0")
        .unwrap();
    dev.write_value(CH1, offset::COMMAND_STATE, &4i32).unwrap();
    assert_eq!(mode_state(&dev), (2, 4));

    let lines = common::streamed_5000_lines();
    let mut busy = 0u32;
    let deadline = Instant::now() + Duration::from_secs(120);
    for p in packets(&lines) {
        loop {
            match dev.write(CH1, offset::STREAM, &p) {
                Ok(()) => break,
                Err(ads::Error::Ads(_, _, 0x708)) => {
                    busy += 1;
                    assert!(Instant::now() < deadline, "stream stalled");
                    std::thread::sleep(Duration::from_millis(1));
                }
                Err(e) => panic!("stream write failed: {e}"),
            }
        }
    }
    // The program ends by itself: READY again.
    while mode_state(&dev).1 != 3 {
        assert!(Instant::now() < deadline, "program did not end");
        std::thread::sleep(Duration::from_millis(5));
    }
    assert!(busy > 0, "a writer faster than the channel sees 0x708");
    let seen: Vec<Vec<u8>> = notes
        .try_iter()
        .map(|n| n.samples().flat_map(|s| s.data.to_vec()).collect())
        .collect();
    assert!(
        seen.iter().any(|d| d.len() >= 8 && d[4] == 4),
        "a notification reported ACTIVE: {seen:?}"
    );
    dev.delete_notification(handle).unwrap();
    drop(client);

    let events = served.finish();
    assert_eq!(ads_common::block_texts(&events), lines);
    assert_eq!(
        ads_common::refusals(&events, 11012),
        u64::from(busy),
        "every 0x708 is one refusal 11012 in the channel, counted in its stretch"
    );
}

#[test]
fn reset_over_ads_empties_the_stream_and_reads_back_ready() {
    let served = Served::start(Params::new(1));
    let client = connect(&served.server);
    let dev = client.device(target());
    dev.write(CH1, offset::STREAM, b"N1 G01 X1000 F100\r\n")
        .unwrap();
    let mut fill = [0u8; 8];
    dev.read_exact(CH1, offset::STREAM_FILL, &mut fill).unwrap();
    assert_eq!(u32::from_le_bytes(fill[0..4].try_into().unwrap()), 19);
    dev.write(CH1, offset::RESET, &[]).unwrap();
    dev.read_exact(CH1, offset::STREAM_FILL, &mut fill).unwrap();
    assert_eq!(u32::from_le_bytes(fill[0..4].try_into().unwrap()), 0);
    assert_eq!(mode_state(&dev).1, 3);
    // A line without CR LF: 0x706 and channel error 21476, readable as the last error.
    let e = dev.write(CH1, offset::STREAM, b"N1 X1\n").unwrap_err();
    assert!(matches!(e, ads::Error::Ads(_, _, 0x706)), "{e}");
    let mut msg = [0u8; 128];
    let n = dev.read(CH1, offset::ERROR_MESSAGE, &mut msg).unwrap();
    assert!(String::from_utf8_lossy(&msg[..n]).starts_with("21476"));
    assert_eq!(mode_state(&dev).1, 6);
    drop(client);
    served.finish();
}

/// `ncchannel serve` with its defaults (NetId 127.0.0.2.1.1) and each local idiom of the `ads`
/// crate: `Source::Request` (the router's port connect) with `AmsNetId::local()`, which the
/// crate rewrites to the NetId the router handed out (`Client::device`); `Source::Auto`
/// (127.0.0.1.1.1 on loopback) with `AmsNetId::local()`; and the device's own NetId. A frame
/// for another NetId answers AMS error 7, logged once per source.
#[test]
fn the_ads_crate_reaches_serve_by_its_local_idioms() {
    let srv = crate::ads_abuse::Serve::start(&[]);
    assert_eq!(srv.device().net_id.to_string(), "127.0.0.2.1.1");
    let timeouts = Timeouts::new(Duration::from_secs(5));
    let client = Client::new(srv.addr(), timeouts, Source::Request).unwrap();
    assert_eq!(
        client.source().netid(),
        AmsNetId::local(),
        "the router hands out its loopback NetId, not the device's"
    );
    let plc = client.device(AmsAddr::new(AmsNetId::local(), 851));
    assert_eq!(plc.get_info().unwrap().name, "Plc30 App");
    let own = client.device(AmsAddr::new(AmsNetId::new(127, 0, 0, 2, 1, 1), 553));
    let info = own.get_info().unwrap();
    assert!(info.name.starts_with("ncchannel"), "{}", info.name);
    let auto = Client::new(srv.addr(), timeouts, Source::Auto).unwrap();
    let system = auto.device(AmsAddr::new(AmsNetId::local(), 10000));
    assert_eq!(system.get_state().unwrap().0, ads::AdsState::Run);
    let other = client.device(AmsAddr::new(AmsNetId::new(5, 6, 7, 8, 1, 1), 553));
    for _ in 0..3 {
        match other.get_info() {
            Err(ads::Error::Ads(_, _, 7)) => {}
            got => panic!("5.6.7.8.1.1 is another device: {got:?}"),
        }
    }
    let line = "for AMS NetId 5.6.7.8.1.1 answered AMS error 7";
    let log = srv.log_once_it_says(line);
    assert_eq!(log.matches(line).count(), 1, "{log}");
}

/// The ADS route service on UDP beside `serve`, through the `ads` crate's `udp` calls:
/// identify (NetId, host name, TwinCAT version, OS) and add-route.
#[test]
fn the_route_service_answers_the_ads_crates_udp_calls() {
    let srv = crate::ads_abuse::Serve::start(&[]);
    let udp = srv.route_service();
    assert_eq!(udp.ip(), srv.addr().ip(), "bound where the TCP server is");
    let host = udp.ip().to_string();
    let to = (host.as_str(), udp.port());
    let own = AmsNetId::new(127, 0, 0, 2, 1, 1);
    assert_eq!(ads::udp::get_netid(to).unwrap(), own);
    let info = ads::udp::get_info(to).unwrap();
    assert_eq!(info.netid, own);
    assert_eq!(info.twincat_version, (3, 1, 4024));
    assert!(!info.hostname.is_empty());
    assert_eq!(info.os_version.4, std::env::consts::OS);
    let client = AmsNetId::new(10, 1, 2, 3, 1, 1);
    ads::udp::add_route(to, client, "127.0.0.1", Some("test"), None, None, false).unwrap();
    let log = srv.log_once_it_says("route added");
    assert!(
        log.contains("route added: 10.1.2.3.1.1, 127.0.0.1"),
        "{log}"
    );
}
