//! The server seen by an independent client: the `ads` crate 0.4 (birkenfeld/ads-rs), which
//! validates flags, invoke ids, addresses and lengths of every response itself.

use std::time::Duration;

use crate::support::ads::*;
use ads::notif::{Attributes, TransmissionMode};
use ads::{AdsState, AmsAddr, AmsNetId, Client, Source, Timeouts};
use ncchannel::ads::objects::offset;

fn connect(srv: &ncchannel::ads::ServerHandle, source_port: u16) -> Client {
    let source = AmsAddr::new(AmsNetId::new(10, 1, 2, 3, 1, 1), source_port);
    Client::new(
        srv.local_addr(),
        Timeouts::new(Duration::from_secs(5)),
        Source::Addr(source),
    )
    .expect("ads crate connects")
}

fn target() -> AmsAddr {
    AmsAddr::new(AmsNetId::new(5, 6, 7, 8, 1, 1), 553)
}

fn ads_code(e: ads::Error) -> u32 {
    match e {
        ads::Error::Ads(_, _, code) => code,
        other => panic!("expected an ADS error, got {other}"),
    }
}

#[test]
fn device_info_state_and_mode_state() {
    let (srv, _b) = server();
    let client = connect(&srv, 40001);
    let dev = client.device(target());
    let info = dev.get_info().unwrap();
    assert_eq!(
        info.name,
        format!("ncchannel {}", env!("CARGO_PKG_VERSION"))
    );
    assert_eq!(dev.get_state().unwrap(), (AdsState::Run, 0));
    let mut ms = [0u8; 8];
    dev.read_exact(CH1, offset::MODE_STATE, &mut ms).unwrap();
    assert_eq!(ms, [2, 0, 0, 0, 3, 0, 0, 0], "AUTOMATIC / READY");
    dev.write_control(AdsState::Run, 0).unwrap();
}

#[test]
fn stream_writes_until_busy_then_0x708() {
    let (srv, b) = server();
    let client = connect(&srv, 40002);
    let dev = client.device(target());
    let packet = [vec![b'G'; 990], b"\r\n".to_vec()].concat();
    for _ in 0..4 {
        dev.write(CH1, offset::STREAM, &packet).unwrap();
    }
    let err = dev.write(CH1, offset::STREAM, &packet).unwrap_err();
    assert_eq!(ads_code(err), 0x708);
    let err = dev.write(CH1, offset::STREAM, b"N10 no crlf").unwrap_err();
    assert_eq!(ads_code(err), 0x706);
    let mut text = [0u8; 128];
    let n = dev.read(CH1, offset::ERROR_MESSAGE, &mut text).unwrap();
    assert!(String::from_utf8_lossy(&text[..n]).starts_with("21476"));
    // Wrong port: the crate reports the AMS header error.
    let none = client.device(AmsAddr::new(AmsNetId::new(5, 6, 7, 8, 1, 1), 800));
    assert_eq!(ads_code(none.get_info().unwrap_err()), 6);
    drop(client);
    srv.shutdown();
    assert_eq!(
        warnings(&b.events(), 11012),
        1,
        "the refused write is the channel's warning 11012"
    );
}

/// V.E. variables in the SDA task (port 552) as TwinSharp `ZeroOffsets.cs` reaches variables:
/// a handle by name (0x46), then plain Read/Write at the handle.
#[test]
fn ve_variables_through_an_sda_handle() {
    let (srv, b) = server();
    b.backend.write_ve(1, "DEPTH", 0.0).unwrap();
    let client = connect(&srv, 40003);
    let sda = client.device(AmsAddr::new(AmsNetId::new(5, 6, 7, 8, 1, 1), 552));
    let mut h = [0u8; 4];
    sda.write_read_exact(0x122301, 0x46, b"V.E.depth", &mut h)
        .unwrap();
    let h = u32::from_le_bytes(h);
    sda.write(0x122301, h, &(-2.25f64).to_le_bytes()).unwrap();
    let mut out = [0u8; 8];
    sda.read_exact(0x122301, h, &mut out).unwrap();
    assert_eq!(f64::from_le_bytes(out), -2.25);
    let err = sda
        .write_read_exact(0x122301, 0x46, b"V.E.nothing", &mut [0u8; 4])
        .unwrap_err();
    assert_eq!(ads_code(err), 0x70C);
}

#[test]
fn notifications_reach_the_crate_on_mode_change() {
    let (srv, _b) = server();
    let client = connect(&srv, 40004);
    let rx = client.get_notification_channel();
    let dev = client.device(target());
    let attrs = Attributes::new(
        8,
        TransmissionMode::ServerOnChange,
        Duration::from_millis(1),
        Duration::from_millis(1),
    );
    let handle = dev
        .add_notification(CH1, offset::MODE_STATE, &attrs)
        .unwrap();
    let first = rx
        .recv_timeout(Duration::from_secs(5))
        .expect("initial sample");
    let s: Vec<_> = first.samples().collect();
    assert_eq!(s[0].handle, handle);
    assert_eq!(s[0].data, [2, 0, 0, 0, 3, 0, 0, 0], "AUTOMATIC / READY");
    dev.write(CH1, offset::COMMAND_MODE, &1i32.to_le_bytes())
        .unwrap();
    let next = rx
        .recv_timeout(Duration::from_secs(5))
        .expect("sample after change");
    let s: Vec<_> = next.samples().collect();
    assert_eq!(s[0].data, [1, 0, 0, 0, 3, 0, 0, 0], "STANDBY / READY");
    dev.delete_notification(handle).unwrap();
}

/// A route added through the route service (the `ads` crate's `udp::add_route`) joins the
/// configured allow-list: a client whose NetId was not listed is served once it is added.
#[test]
fn a_route_added_over_udp_lets_its_client_through_the_allow_list() {
    let listed = "10.9.9.9.1.1".parse().unwrap();
    let (srv, _b) = server_with(ncchannel::ads::ServerConfig {
        allow: vec![listed],
        route_service: true,
        ..Default::default()
    });
    let udp = srv.route_service_addr().expect("route service runs");
    let id = ncchannel::vocab::ams::AmsNetId([10, 1, 2, 3, 1, 1]);
    let route = ncchannel::ads::RouteEntry::NetId(id);
    assert!(!srv.routes().contains(&route));
    let host = udp.ip().to_string();
    ads::udp::add_route(
        (host.as_str(), udp.port()),
        AmsNetId::new(10, 1, 2, 3, 1, 1),
        "a-host-name",
        None,
        None,
        None,
        false,
    )
    .unwrap();
    assert_eq!(srv.routes(), [listed, route], "a host name adds no IP");
    let client = connect(&srv, 40021);
    assert_eq!(
        client.device(target()).get_state().unwrap().0,
        AdsState::Run
    );
}

/// With the route service's UDP port held by someone else (another router, a second serve on
/// another TCP port) the server still serves TCP, without a route service.
#[test]
fn a_taken_route_service_port_leaves_the_tcp_server_serving() {
    let _held = std::net::UdpSocket::bind("127.0.0.1:48899");
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .unwrap()
        .port();
    let channels = Channels::start(1);
    let config = ncchannel::ads::ServerConfig {
        bind: std::net::SocketAddr::from(([127, 0, 0, 1], port)),
        route_service: true,
        ..Default::default()
    };
    let srv = ncchannel::ads::spawn(config, std::sync::Arc::clone(&channels.backend)).unwrap();
    assert_eq!(srv.route_service_addr(), None);
    let client = connect(&srv, 40022);
    assert_eq!(
        client.device(target()).get_state().unwrap().0,
        AdsState::Run
    );
}

#[test]
fn router_port_request_works_with_the_crate() {
    let (srv, _b) = server();
    let client = Client::new(
        srv.local_addr(),
        Timeouts::new(Duration::from_secs(5)),
        Source::Request,
    )
    .unwrap();
    assert_eq!(client.source().netid(), AmsNetId::new(127, 0, 0, 1, 1, 1));
    let dev = client.device(target());
    assert_eq!(dev.get_state().unwrap().0, AdsState::Run);
}

/// The `ads` crate's symbol helpers against the PLC runtime (851): `get_symbol_info` (upload
/// info 3, data-type and symbol uploads, decoded by the crate), `get_location`/`get_size`
/// (0xF007) and a handle read of what they name.
#[test]
fn symbol_and_type_uploads_decode_with_the_ads_crate() {
    let (srv, _b) = server();
    let client = connect(&srv, 40009);
    let dev = client.device(AmsAddr::new(AmsNetId::new(5, 6, 7, 8, 1, 1), 851));
    let (symbols, types) = ads::symbol::get_symbol_info(dev).unwrap();
    let name = "HLI_Global_Variables.gpCh[0]^.channel_mc_control.mode_and_state.state_r";
    let state = symbols
        .iter()
        .find(|s| s.name == name)
        .expect("state_r uploaded");
    assert_eq!((state.typ.as_str(), state.size), ("HLI_IMCM_MODE_STATE", 8));
    let ty = &types["HLI_IMCM_MODE_STATE"];
    let fields: Vec<_> = ty
        .fields
        .iter()
        .map(|f| (f.name.as_str(), f.offset))
        .collect();
    assert_eq!(fields, [("mode", Some(0)), ("state", Some(4))]);
    assert_eq!(types["ARRAY [0..19] OF TECHNO_UNIT_CH"].array, [(0, 19)]);
    let member = format!("{name}.state");
    assert_eq!(ads::symbol::get_size(dev, &member).unwrap(), 4);
    let (group, offset) = ads::symbol::get_location(dev, &member).unwrap();
    let mut v = [0u8; 4];
    dev.read_exact(group, offset, &mut v).unwrap();
    assert_eq!(u32::from_le_bytes(v), 3, "READY");
}

#[test]
fn sum_add_and_delete_notifications_answer_each_sub_request() {
    use ads::client::{AddNotifRequest, DelNotifRequest};
    let (srv, _b) = server();
    let client = connect(&srv, 40005);
    let rx = client.get_notification_channel();
    let dev = client.device(target());
    let on_change = Attributes::new(
        8,
        TransmissionMode::ServerOnChange,
        Duration::from_millis(1),
        Duration::from_millis(1),
    );
    let cyclic = Attributes::new(
        8,
        TransmissionMode::ServerCycle,
        Duration::from_millis(10),
        Duration::from_millis(10),
    );
    let mut adds = [
        AddNotifRequest::new(CH1, offset::MODE_STATE, &on_change),
        // The stream object cannot be read: its own error, the others are made.
        AddNotifRequest::new(CH1, offset::STREAM, &on_change),
        AddNotifRequest::new(CH1, offset::BLOCK_COUNTER, &cyclic),
    ];
    dev.add_notification_multi(&mut adds).unwrap();
    let mode = adds[0].handle().unwrap();
    assert_eq!(ads_code(adds[1].handle().unwrap_err()), 0x704);
    let blocks = adds[2].handle().unwrap();
    assert_ne!(mode, blocks);
    // Both handles send their first samples.
    let mut seen = std::collections::BTreeSet::new();
    while seen.len() < 2 {
        let n = rx
            .recv_timeout(Duration::from_secs(5))
            .expect("first samples of both handles");
        seen.extend(n.samples().map(|s| s.handle));
    }
    assert_eq!(seen, [mode, blocks].into_iter().collect());
    let mut dels = [
        DelNotifRequest::new(mode),
        DelNotifRequest::new(blocks),
        DelNotifRequest::new(blocks + 1000),
    ];
    dev.delete_notification_multi(&mut dels).unwrap();
    dels[0].ensure().unwrap();
    dels[1].ensure().unwrap();
    assert_eq!(ads_code(dels[2].ensure().unwrap_err()), 0x714);
    // Deleted: a single delete of the same handle is now refused.
    assert_eq!(ads_code(dev.delete_notification(mode).unwrap_err()), 0x714);
}
