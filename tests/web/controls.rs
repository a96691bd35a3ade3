//! The operator controls: refused (403) unless the view was started with them, refused
//! without the page's header, and applied through the channel's door when allowed.

use std::time::Duration;

use ncchannel::http::ControlAccess;
use ncchannel::vocab::mode::State;

use super::client::{self, Events};
use super::view;

const WITHIN: Duration = Duration::from_secs(20);

#[test]
fn controls_are_refused_without_the_option() {
    let (web, channels) = view(ControlAccess::Refused);
    let addr = web.local_addr();
    for (action, body) in [
        ("start", "square.nc"),
        ("hold", ""),
        ("reset", ""),
        ("override", "50"),
        ("mdi", "G01 X10 F1000"),
        ("jog", "X1"),
        ("run-from-line", "square.nc\nN40"),
    ] {
        let r = client::control(addr, 1, action, body);
        assert_eq!(r.status, 403, "{action}");
        assert!(r.body.contains("--http-controls"), "{}", r.body);
    }
    let s = channels.status(1);
    assert_eq!(s.state, State::Ready);
    assert_eq!(s.program, None);
    assert_eq!(client::get(addr, "/controls").body, "off");
}

#[test]
fn a_control_without_the_page_header_is_refused() {
    let (web, channels) = view(ControlAccess::Allowed);
    let r = client::request(
        web.local_addr(),
        "POST",
        "/control/1/start",
        &[],
        "square.nc",
    );
    assert_eq!(r.status, 403);
    assert!(r.body.contains("X-Ncchannel-Control"), "{}", r.body);
    assert_eq!(channels.status(1).state, State::Ready);
}

#[test]
fn allowed_controls_go_through_the_door() {
    let (web, channels) = view(ControlAccess::Allowed);
    let addr = web.local_addr();
    assert_eq!(client::get(addr, "/controls").body, "on");
    let r = client::control(addr, 1, "start", "square.nc");
    assert_eq!((r.status, r.body.as_str()), (200, "done"));
    channels.wait_for(1, WITHIN, |s| s.state == State::Active);
    assert_eq!(client::control(addr, 1, "override", "50").status, 200);
    let mut events = Events::open(addr);
    events.until(WITHIN, |name, d| {
        (name == "status" && client::channel(d, 1)?["override_pct"] == 50.0).then_some(())
    });
    let bad = client::control(addr, 1, "override", "250");
    assert_eq!(bad.status, 409);
    assert!(bad.body.contains("250"), "{}", bad.body);
    assert_eq!(client::control(addr, 1, "hold", "").status, 200);
    channels.wait_for(1, WITHIN, |s| s.state == State::Hold);
    assert_eq!(client::control(addr, 1, "resume", "").status, 200);
    channels.wait_for(1, WITHIN, |s| s.state == State::Active);
    // A second start while running: the channel's own refusal, as ADS would hear it.
    let busy = client::control(addr, 1, "start", "square.nc");
    assert_eq!(busy.status, 409, "{}", busy.body);
    assert_eq!(client::control(addr, 1, "reset", "").status, 200);
    channels.wait_for(1, WITHIN, |s| s.state == State::Ready);
    assert_eq!(client::control(addr, 9, "hold", "").status, 404);
    assert_eq!(client::control(addr, 1, "launch", "").status, 400);
}

/// A page served from a rebinding name (its `Host` is that name, resolved to loopback) is
/// answered 421 and commands nothing, even with `--http-controls`.
#[test]
fn a_rebinding_host_is_refused_and_executes_nothing() {
    let (web, channels) = view(ControlAccess::Allowed);
    let addr = web.local_addr();
    let port = addr.port();
    for host in [
        format!("rebind.test:{port}"),
        "rebind.test".to_string(),
        String::new(),
    ] {
        let r = client::raw(
            addr,
            &format!(
                "POST /control/1/start HTTP/1.1\r\nHost: {host}\r\nX-Ncchannel-Control: 1\r\n\
                 Content-Length: 9\r\n\r\nsquare.nc"
            ),
        );
        assert_eq!(r.status, 421, "{host}: {}", r.body);
        let get = client::raw(
            addr,
            &format!("GET /events HTTP/1.1\r\nHost: {host}\r\n\r\n"),
        );
        assert_eq!(get.status, 421, "{host}");
    }
    let s = channels.status(1);
    assert_eq!((s.state, s.program), (State::Ready, None));
    // Loopback names with the port are answered.
    for host in [format!("localhost:{port}"), format!("127.0.0.1:{port}")] {
        let r = client::raw(
            addr,
            &format!("GET /controls HTTP/1.1\r\nHost: {host}\r\n\r\n"),
        );
        assert_eq!((r.status, r.body.as_str()), (200, "on"), "{host}");
    }
}

/// A name given for a reverse proxy is answered.
#[test]
fn an_allowed_proxy_host_is_answered() {
    let params = super::Params::new(1);
    let channels = super::Channels::from_params(params);
    let config = ncchannel::http::HttpConfig {
        bind: "127.0.0.1:0".parse().unwrap(),
        allow_non_loopback: false,
        controls: ControlAccess::Refused,
        allow_hosts: vec!["cnc.example".to_string()],
    };
    let web = ncchannel::http::spawn(&config, std::sync::Arc::clone(&channels.backend), None)
        .expect("web view starts");
    let addr = web.local_addr();
    let r = client::raw(addr, "GET /controls HTTP/1.1\r\nHost: cnc.example\r\n\r\n");
    assert_eq!(r.status, 200);
    let r = client::raw(
        addr,
        "GET /controls HTTP/1.1\r\nHost: other.example\r\n\r\n",
    );
    assert_eq!(r.status, 421);
}

/// A state-changing request whose `Origin` is not the view's own is refused 403.
#[test]
fn a_foreign_origin_is_refused() {
    let (web, channels) = view(ControlAccess::Allowed);
    let addr = web.local_addr();
    let r = client::request(
        addr,
        "POST",
        "/control/1/start",
        &["X-Ncchannel-Control: 1", "Origin: http://rebind.test"],
        "square.nc",
    );
    assert_eq!(r.status, 403, "{}", r.body);
    assert!(r.body.contains("Origin"), "{}", r.body);
    assert_eq!(channels.status(1).state, State::Ready);
    let own = format!("Origin: http://{addr}");
    let r = client::request(
        addr,
        "POST",
        "/control/1/start",
        &["X-Ncchannel-Control: 1", &own],
        "square.nc",
    );
    assert_eq!((r.status, r.body.as_str()), (200, "done"));
}

/// Two `Content-Length` headers are refused with 400 and command nothing.
#[test]
fn two_content_lengths_are_refused() {
    let (web, channels) = view(ControlAccess::Allowed);
    let r = client::request(
        web.local_addr(),
        "POST",
        "/control/1/start",
        &["X-Ncchannel-Control: 1", "Content-Length: 9"],
        "square.nc",
    );
    assert_eq!(r.status, 400, "{}", r.body);
    assert!(r.body.contains("Content-Length"), "{}", r.body);
    assert_eq!(channels.status(1).state, State::Ready);
}

/// Run from line: by an N number before the program ever ran, by a listing line after; the
/// first block that runs is the one asked for (block search), and the line is refused with
/// the reason before the channel has the text.
#[test]
fn run_from_line_starts_at_the_block_asked_for() {
    let (web, channels) = view(ControlAccess::Allowed);
    let addr = web.local_addr();
    let early = client::control(addr, 1, "run-from-line", "square.nc\n5");
    assert_eq!(early.status, 409, "{}", early.body);
    assert!(early.body.contains("N number"), "{}", early.body);
    assert_eq!(
        client::control(addr, 1, "run-from-line", "square.nc\nN40").status,
        200
    );
    let first_block = |events: &mut Events| {
        events.until(WITHIN, |name, d| {
            let c = client::channel(d, 1).filter(|_| name == "status")?;
            c["block_n"].as_u64()
        })
    };
    let n = first_block(&mut Events::open(addr));
    assert!(n >= 40, "the run starts at N40, not N{n}");
    assert_eq!(client::control(addr, 1, "reset", "").status, 200);
    channels.wait_for(1, WITHIN, |s| s.state == State::Ready);
    // The channel has the text now: line 6 of the listing is N50.
    assert_eq!(
        client::control(addr, 1, "run-from-line", "square.nc\n6").status,
        200
    );
    let n = first_block(&mut Events::open(addr));
    assert!(n >= 50, "the run starts at N50, not N{n}");
    assert_eq!(
        client::control(addr, 1, "run-from-line", "square.nc\n0").status,
        400
    );
}

/// MDI and jog move the axes through the channel's stream interface (the streaming program
/// started, the block and M30 written, as a streaming client does), and come back READY.
#[test]
fn mdi_and_jog_move_the_axes() {
    let (web, channels) = view(ControlAccess::Allowed);
    let addr = web.local_addr();
    let r = client::control(addr, 1, "mdi", "G01 X10 Y5 F3000");
    assert_eq!((r.status, r.body.as_str()), (200, "done"));
    let s = channels.wait_for(1, WITHIN, |s| {
        s.state == State::Ready && s.positions[0].1 == 10.0
    });
    assert_eq!(s.positions[1].1, 5.0);
    assert_eq!(client::control(addr, 1, "jog", "Y-2").status, 200);
    let s = channels.wait_for(1, WITHIN, |s| {
        s.state == State::Ready && (s.positions[1].1 - 3.0).abs() < 1e-9
    });
    assert_eq!(s.positions[0].1, 10.0, "a jog moves one axis");
    // While a program runs, MDI is the channel's refusal.
    assert_eq!(client::control(addr, 1, "start", "square.nc").status, 200);
    channels.wait_for(1, WITHIN, |s| s.state == State::Active);
    let busy = client::control(addr, 1, "mdi", "G01 X0");
    assert_eq!(busy.status, 409, "{}", busy.body);
    assert!(busy.body.contains("not possible"), "{}", busy.body);
}
