//! The live view in a real headless browser: Debian's chromium driven by playwright-core
//! (tests/node/live_view_test.js) against two views of the same channels, one read-only and
//! one with controls. Needs chromium and `npm ci --prefix tests/node`, so it is ignored by
//! default; `.ci/run` installs both and runs it:
//!
//! `cargo test --test web -- --ignored browser`

use std::sync::Arc;

use ncchannel::http::{spawn, ControlAccess, HttpConfig};
use ncchannel::machine::Op;
use ncchannel::vocab::mode::State;
use serde_json::Value;

use super::{run_page_script, view};

/// The N number a listing line or the DRO's block field starts with (`N20 G01 …`, `N20 (#8)`).
fn n_number(text: &str) -> Option<u32> {
    let digits: String = text
        .trim()
        .strip_prefix('N')?
        .chars()
        .take_while(char::is_ascii_digit)
        .collect();
    digits.parse().ok()
}

#[test]
#[ignore = "needs chromium and tests/node/node_modules: .ci/run installs them"]
fn browser_shows_a_running_channel_its_line_and_its_errors() {
    let (read_only, channels) = view(ControlAccess::Refused);
    let config = HttpConfig {
        bind: "127.0.0.1:0".parse().unwrap(),
        allow_non_loopback: false,
        controls: ControlAccess::Allowed,
        allow_hosts: Vec::new(),
    };
    let with_controls = spawn(&config, Arc::clone(&channels.backend), None).unwrap();
    channels.command(2, Op::Start("streaming.nc".into()));
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/node/live_view_test.js");
    let args = [
        format!("http://{}/", read_only.local_addr()),
        format!("http://{}/", with_controls.local_addr()),
    ];
    let seen = run_page_script(script, &args, |line| {
        if line != "READY_FOR_ERROR" {
            return false;
        }
        // A syntax error on channel 2's stream while the page watches.
        let bad = Op::WriteStream(b"N10 G01 X1 Y=\r\n"[..].into());
        channels.backend.call(2, bad).unwrap();
        true
    });

    let refused = seen["refused"].as_str().unwrap();
    assert!(
        refused.contains("403") && refused.contains("--http-controls"),
        "{refused}"
    );
    assert_eq!(seen["state_after_refusal"], "READY");
    let xs: Vec<f64> = seen["x"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_str().unwrap().parse().unwrap())
        .collect();
    assert!(xs.windows(2).all(|w| w[0] != w[1]), "{xs:?}");
    let line = seen["current_line"].as_str().unwrap();
    let block = seen["block"].as_str().unwrap();
    assert!(n_number(line).is_some(), "{line}");
    assert!(seen["listing_lines"].as_u64().unwrap() >= 8);
    // The highlighted line and the DRO's block come from one update, at most one block apart
    // (the page reads them one after the other while the program runs).
    let (n_line, n_block) = (n_number(line).unwrap(), n_number(block).unwrap());
    assert!(n_line.abs_diff(n_block) <= 10, "{line} / {block}");
    assert_eq!(seen["held"], true);
    assert_eq!(channels.status(1).state, State::Hold);
    let error = seen["error"].as_str().unwrap();
    let code: u32 = error.split(':').next().unwrap().parse().unwrap();
    assert!((20_000..30_000).contains(&code), "{error}");
    assert_eq!(seen["ch2_state"], "ERROR");
    assert_eq!(channels.status(2).state, State::Error);
    assert_eq!(
        seen["foreign"],
        Value::Array(Vec::new()),
        "only the view's own address"
    );
}

/// A page served from a rebinding name resolved to loopback commands nothing, even with
/// `--http-controls`: the page and its start are answered 421.
#[test]
#[ignore = "needs chromium and tests/node/node_modules: .ci/run installs them"]
fn browser_on_a_rebinding_name_cannot_start_a_program() {
    let (web, channels) = view(ControlAccess::Allowed);
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/node/guarded_view_test.js"
    );
    let args = ["rebind".to_string(), web.local_addr().port().to_string()];
    let seen = run_page_script(script, &args, |_| false);
    assert_eq!(seen["page_status"], 421);
    assert_eq!(seen["start_status"], 421);
    let s = channels.status(1);
    assert_eq!((s.state, s.program), (State::Ready, None));
}

/// A page answered 503 (every page slot taken) says it retries and goes live once a slot
/// frees.
#[test]
#[ignore = "needs chromium and tests/node/node_modules: .ci/run installs them"]
fn browser_refused_for_want_of_a_slot_retries_and_goes_live() {
    let (web, _channels) = view(ControlAccess::Refused);
    let addr = web.local_addr();
    let mut held: Vec<_> = (0..ncchannel::http::MAX_PAGE_CONNECTIONS)
        .map(|_| super::client::Events::open(addr))
        .collect();
    assert!(held.iter().all(|e| e.status == 200));
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/node/guarded_view_test.js"
    );
    let args = ["full".to_string(), format!("http://{addr}/")];
    let seen = run_page_script(script, &args, |line| {
        if line != "RETRYING" {
            return false;
        }
        held.clear();
        true
    });
    assert!(
        seen["refused"].as_str().unwrap().contains("retrying in"),
        "{seen}"
    );
    assert!(seen["retries"].as_u64().unwrap() >= 1);
    assert_eq!(seen["last"], "live");
}
