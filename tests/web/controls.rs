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
