//! The technology panel: the units waiting for the PLC in the `status` event (channel list
//! `m_synch[25] MVS_SVS`, `m_prozess_zeit[25] 3000000`, README "Technology functions: the PLC
//! half"), acknowledged by a PLC writing `done_w` through the door as ADS does, and in a real
//! headless browser without a PLC (the channel acknowledges after the 3 s process time).

use std::sync::Arc;
use std::time::Duration;

use ncchannel::channel::techno::{TechnoWrite, UnitSet};
use ncchannel::http::{spawn, ControlAccess, HttpConfig, HttpHandle};
use ncchannel::machine::{Op, Reply};
use serde_json::Value;

use super::client::{self, Events};
use super::run_page_script;
use super::support::ads::{Channels, Params};

const WITHIN: Duration = Duration::from_secs(20);

/// M25 waits before N30's motion until it is acknowledged.
pub const TECHNO: &str = "%techno\r\nN10 G01 X10 F6000\r\nN20 M25\r\nN30 G01 X20\r\nN40 M30\r\n";

/// One channel ticking in real time whose list defines M25 as MVS_SVS with a 3 s process
/// time, `techno.nc` in its program folder, behind a read-only view.
fn techno_view() -> (HttpHandle, Channels) {
    let params = Params::new(1);
    params.program("techno.nc", TECHNO);
    std::fs::write(
        params.dir.path().join("params/channel1.lis"),
        "streaming_prog_file streaming.nc\nm_synch[25] MVS_SVS\nm_prozess_zeit[25] 3000000\n",
    )
    .unwrap();
    let channels = Channels::from_params(params);
    let config = HttpConfig {
        bind: "127.0.0.1:0".parse().unwrap(),
        allow_non_loopback: false,
        controls: ControlAccess::Refused,
        allow_hosts: Vec::new(),
    };
    let web = spawn(&config, Arc::clone(&channels.backend), None).expect("web view starts");
    (web, channels)
}

fn techno_write(channels: &Channels, w: TechnoWrite) {
    let reply = channels.backend.call(1, Op::Techno(w));
    assert!(matches!(reply, Ok(Reply::Techno(Ok(())))), "{reply:?}");
}

#[test]
fn the_status_event_shows_m25_waiting_for_the_plc_until_done_w() {
    let (web, channels) = techno_view();
    techno_write(&channels, TechnoWrite::PlcPresent(true));
    let mut events = Events::open(web.local_addr());
    // Idle: nothing waits, nothing encoded. The feed polls with no page connected, so the
    // first event may be the snapshot taken before the write: wait for the one after it.
    let idle = events.until(WITHIN, |name, d| {
        let c = client::channel(d, 1).filter(|_| name == "status")?;
        (c["techno"]["plc_present"] == true).then(|| c.clone())
    });
    assert_eq!(idle["techno"]["waiting"], Value::Array(Vec::new()));
    assert_eq!(idle["techno"]["plc_present"], true);
    channels.command(1, Op::Start("techno.nc".into()));
    let waiting = events.until(WITHIN, |name, d| {
        let t = &client::channel(d, 1).filter(|_| name == "status")?["techno"];
        (t["waiting"].as_array()?.len() == 1 && t["waiting"][0]["waited_s"].as_f64()? > 0.2)
            .then(|| t.clone())
    });
    let w = &waiting["waiting"][0];
    assert_eq!(w["function"], "M25", "{waiting}");
    assert_eq!(w["sync"], "MVS_SVS");
    assert_eq!(w["set"], "std");
    assert_eq!(w["unit"], 0);
    assert_eq!(w["please"], true, "not fetched");
    assert_eq!(w["process_time_us"], 3_000_000);
    assert_eq!(w["line"], 3);
    assert!(w["output_at_s"].as_f64().unwrap() > 0.0);
    assert_eq!(waiting["output"], 1);
    assert_eq!(waiting["acknowledged"], 0);
    // The PLC fetches and acknowledges, as TwinSharp's TechnologyProcesses.cs does.
    for w in [
        TechnoWrite::Please {
            set: UnitSet::Std,
            unit: 0,
            value: false,
        },
        TechnoWrite::Done {
            set: UnitSet::Std,
            unit: 0,
            value: true,
        },
    ] {
        techno_write(&channels, w);
    }
    let done = events.until(WITHIN, |name, d| {
        let t = &client::channel(d, 1).filter(|_| name == "status")?["techno"];
        (t["acknowledged"] == 1).then(|| t.clone())
    });
    assert_eq!(done["waiting"], Value::Array(Vec::new()), "{done}");
    assert_eq!(done["output"], 1);
}

#[test]
#[ignore = "needs chromium and tests/node/node_modules: .ci/run installs them"]
fn browser_shows_m25_waiting_then_gone_after_its_process_time() {
    let (web, channels) = techno_view();
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/web/techno_view_test.js");
    let args = [format!("http://{}/", web.local_addr())];
    let seen = run_page_script(script, &args, |line| {
        if line != "READY" {
            return false;
        }
        // The page is live: start the program now, so its M25 is output while it watches.
        channels.command(1, Op::Start("techno.nc".into()));
        true
    });
    assert_eq!(seen["function"], "M25");
    assert_eq!(seen["sync"], "MVS_SVS");
    assert_eq!(seen["unit"], "std 0");
    assert!(seen["plc"].as_str().unwrap().contains("no PLC"), "{seen}");
    assert_eq!(seen["none_shown_after"], true);
    assert!(
        seen["counts_after"]
            .as_str()
            .unwrap()
            .contains("acknowledged 1"),
        "{seen}"
    );
    // Shown until the channel acknowledged it, 3 s after its output (the page saw it within
    // a few updates of the output).
    let shown = seen["shown_ms"].as_f64().unwrap();
    assert!((2_000.0..20_000.0).contains(&shown), "{seen}");
    let s = channels.status(1);
    assert_eq!(s.techno_open.stats.acknowledged, 1);
}
