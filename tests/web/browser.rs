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
    let lists = ncchannel::params::load(&channels.params.startup()).unwrap();
    with_controls.set_previewer(ncchannel::cli::preview::previewer(
        lists,
        ncchannel::Loader::start(),
    ));
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
    assert!(seen["preview_points"].as_u64().unwrap() >= 2, "{seen}");
    // MDI X5 and a jog of Y by 1 mm moved the axes (the read-only page could not).
    let dro = seen["mdi_jog"].as_str().unwrap();
    assert!(dro.contains("5.000") && dro.contains("1.000"), "{dro}");
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

/// Channel 1's streamed program: a rapid, two cuts with the spindle on, then a slow zigzag
/// longer than the stream buffer (the writer is refused with 11012 and offers again).
fn streamed_program() -> Vec<String> {
    let mut lines: Vec<String> = [
        "N1 G90 G17 G54",
        "N2 S1000 M3",
        "N3 G0 X10 Y0",
        "N4 G1 X20 F3000",
        "N5 G1 Y10",
    ]
    .iter()
    .map(|l| l.to_string())
    .collect();
    for i in 6..400 {
        let x = 20 + i % 2;
        lines.push(format!(
            "N{i} G1 X{x} Y{:.2} F300",
            10.0 + f64::from(i) * 0.05
        ));
    }
    lines
}

/// A streamed program's lines, the path since its start (rapid dashed) and the overview of
/// four channels in a page opened late at 1280×800.
#[test]
#[ignore = "needs chromium and tests/node/node_modules: .ci/run installs them"]
fn browser_shows_a_stream_its_path_since_the_start_and_every_channel() {
    use super::support::ads::{Channels, Params};
    use std::sync::atomic::{AtomicBool, Ordering};
    let channels = Channels::from_params(Params::new(4));
    let config = HttpConfig {
        bind: "127.0.0.1:0".parse().unwrap(),
        allow_non_loopback: false,
        controls: ControlAccess::Refused,
        allow_hosts: Vec::new(),
    };
    let web = spawn(&config, Arc::clone(&channels.backend), None).unwrap();
    channels.command(1, Op::Start("streaming.nc".into()));
    let stop = Arc::new(AtomicBool::new(false));
    let writer = {
        let backend = Arc::clone(&channels.backend);
        let stop = Arc::clone(&stop);
        std::thread::spawn(move || {
            for line in streamed_program() {
                let packet: Arc<[u8]> = format!("{line}\r\n").into_bytes().into();
                // Each call waits for the tick that serves it: offered again once a tick.
                while !stop.load(Ordering::Relaxed) {
                    let r = backend.call(1, Op::WriteStream(Arc::clone(&packet)));
                    if matches!(r, Ok(ncchannel::machine::Reply::Stream(Ok(())))) {
                        break;
                    }
                }
            }
        })
    };
    // The page connects after the rapid and the first cuts have run.
    channels.wait_for(1, std::time::Duration::from_secs(20), |s| s.blocks >= 8);
    channels.command(4, Op::Start("streaming.nc".into()));
    let bad = Op::WriteStream(b"N10 G01 X1 Y=\r\n"[..].into());
    channels.backend.call(4, bad).unwrap();
    channels.wait_for(4, std::time::Duration::from_secs(5), |s| {
        s.state == State::Error
    });
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/node/live_view_stream_test.js"
    );
    let seen = run_page_script(script, &[format!("http://{}/", web.local_addr())], |_| {
        false
    });
    stop.store(true, Ordering::Relaxed);
    writer.join().unwrap();

    let ov4 = seen["ov4"].as_str().unwrap();
    assert!(
        ov4.contains("ERROR") && ov4.contains("streaming.nc"),
        "{ov4}"
    );
    assert!(ov4.contains("line 1"), "the error names its line: {ov4}");
    assert_eq!(seen["ch4_link"], "#ch4");
    assert!(
        seen["badges"]
            .as_str()
            .unwrap()
            .contains("AUTOMATIC ACTIVE"),
        "{seen}"
    );
    let current = seen["current"].as_str().unwrap();
    assert!(n_number(current).is_some_and(|n| n >= 6), "{current}");
    assert!(seen["done_lines"].as_u64().unwrap() >= 5, "{seen}");
    // The path since the start, though the page came late: the rapid from X0 to X10 (dashed)
    // and the cuts to X20 Y10 are in it.
    assert!(seen["rapid_segments"].as_u64().unwrap() >= 1, "{seen}");
    assert!(seen["cut_segments"].as_u64().unwrap() >= 2, "{seen}");
    let b: Vec<f64> = seen["path_bounds"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert!(
        b[0] <= 0.001 && b[1] <= 0.001 && b[2] >= 20.0 && b[3] >= 10.0,
        "{b:?}"
    );
    let spindle = seen["spindle"].as_str().unwrap();
    assert!(
        spindle.contains("M03") && spindle.contains("S1000"),
        "{spindle}"
    );
    assert!(seen["tool"].as_str().unwrap().starts_with('T'), "{seen}");
    let g = seen["gcodes"].as_str().unwrap();
    assert!(
        g.contains("G17") && g.contains("G90") && g.contains("G54"),
        "{g}"
    );
    assert_eq!(seen["feed"], "F300 mm/min", "the executing block's F");
    assert_eq!(seen["start_disabled"], true);
}

/// `serve --soak --http`: the page shows the soak's counters and invariants while an
/// `ncchannel stream` client feeds the soaked channel.
#[test]
#[ignore = "needs chromium and tests/node/node_modules: .ci/run installs them"]
fn browser_watches_a_soak() {
    use std::io::{BufRead, BufReader};
    use std::process::{Command, Stdio};
    let bin = env!("CARGO_BIN_EXE_ncchannel");
    let dir = tempfile::tempdir().unwrap();
    let params = concat!(env!("CARGO_MANIFEST_DIR"), "/params/soak/startup.lis");
    let sc = dir.path().join("soak.toml");
    std::fs::write(
        &sc,
        format!("params = {params:?}\nseed = 3\n[invariants]\nexpected_errors = []\n"),
    )
    .unwrap();
    let mut nc = String::new();
    for n in 1..=3000 {
        nc.push_str(&format!(
            "N{n} G01 X{:.2} Y0 F20000\n",
            f64::from(n % 40) * 0.05
        ));
    }
    let file = dir.path().join("client.nc");
    std::fs::write(&file, nc).unwrap();
    let mut serve = Command::new(bin)
        .args(["serve", "--bind", "127.0.0.1:0", "--http", "127.0.0.1:0"])
        .arg("--soak")
        .arg(&sc)
        .args(["--seconds", "60"])
        .stderr(Stdio::piped())
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let mut err = BufReader::new(serve.stderr.take().unwrap());
    let (mut web, mut ads) = (None, None);
    let mut line = String::new();
    while web.is_none() || ads.is_none() {
        line.clear();
        assert!(err.read_line(&mut line).unwrap() > 0, "serve ended early");
        if let Some(rest) = line.split("web view on ").nth(1) {
            web = rest.split(' ').next().map(str::to_string);
        }
        if let Some(rest) = line.split("listening on ").nth(1) {
            ads = rest.split(' ').next().map(str::to_string);
        }
    }
    // The rest of stderr drained, so serve never blocks on it.
    let drain = std::thread::spawn(move || std::io::copy(&mut err, &mut std::io::sink()));
    let mut client = Command::new(bin)
        .args(["stream", "--target", &ads.unwrap()])
        .arg(&file)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/node/soak_view_test.js");
    let seen = run_page_script(script, &[web.unwrap()], |_| false);
    // The test's own children, by their handles.
    let _ = client.kill();
    let _ = client.wait();
    let _ = serve.kill();
    let _ = serve.wait();
    let _ = drain.join();
    let number = |k: &str| seen[k].as_str().unwrap().parse::<u64>().unwrap();
    assert!(number("blocks") > 100, "{seen}");
    assert!(number("lines") >= number("blocks"), "{seen}");
    let invariants = seen["invariants"].as_array().unwrap();
    assert!(
        invariants
            .iter()
            .all(|v| v.as_str().unwrap().starts_with("holds: ")),
        "{seen}"
    );
}
