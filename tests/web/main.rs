//! The live web view of `serve --http`: the page and its event stream over real sockets
//! (`feed`), the operator controls (`controls`), the technology units waiting for the PLC
//! (`techno`), what it costs the runtime (`bench`), and the page in a real headless browser (`browser`, run by `.ci/run`; ignored here only when no
//! chromium is installed).

#[path = "../support/mod.rs"]
mod support;

mod bench;
mod browser;
mod client;
mod controls;
mod feed;
mod slowloris;
mod techno;

use std::sync::Arc;

use ncchannel::http::{spawn, ControlAccess, HttpConfig, HttpHandle};
use support::ads::{Channels, Params};

/// Channel 1's program: a square with a rounded corner at 10 mm/s (17 s), long enough to watch.
pub const SQUARE: &str = "%square\r\nN10 G90 G01 X0 Y0 F600\r\nN20 G01 X40 Y0\r\n\
N30 G03 X50 Y10 I0 J10\r\nN40 G01 X50 Y40\r\nN50 G01 X0 Y40\r\nN60 G01 X0 Y0\r\nN70 M30\r\n";

/// Two real channels ticking at 1 ms (channel 1 with `square.nc` in its program folder,
/// both with the streaming program) behind a web view with `controls`.
pub fn view(controls: ControlAccess) -> (HttpHandle, Channels) {
    let params = Params::new(2);
    params.program("square.nc", SQUARE);
    let channels = Channels::from_params(params);
    let config = HttpConfig {
        bind: "127.0.0.1:0".parse().unwrap(),
        allow_non_loopback: false,
        controls,
        allow_hosts: Vec::new(),
    };
    let web = spawn(&config, Arc::clone(&channels.backend), None).expect("web view starts");
    let lists = ncchannel::params::load(&channels.params.startup()).expect("lists load");
    web.set_previewer(ncchannel::cli::preview::previewer(
        lists,
        ncchannel::Loader::start(),
    ));
    (web, channels)
}

/// Run a page script (playwright-core driving chromium) with `args`; each line it prints goes
/// to `cue` (which acts on the lines it knows and answers whether it took the line); the last
/// other line is the JSON of what the page saw, returned once the script succeeded.
pub fn run_page_script(
    script: &str,
    args: &[String],
    mut cue: impl FnMut(&str) -> bool,
) -> serde_json::Value {
    use std::io::{BufRead, BufReader, Read};
    use std::process::{Command, Stdio};
    let node = std::env::var("NCCHANNEL_NODE").unwrap_or_else(|_| "node".into());
    let mut child = Command::new(&node)
        .arg(script)
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("{node} runs: {e}"));
    let mut stderr = child.stderr.take().unwrap();
    let errors = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = stderr.read_to_string(&mut s);
        s
    });
    let mut last = String::new();
    for line in BufReader::new(child.stdout.take().unwrap()).lines() {
        let line = line.unwrap();
        if !cue(&line) {
            last = line;
        }
    }
    let status = child.wait().unwrap();
    let stderr = errors.join().unwrap();
    assert!(status.success(), "{stderr}");
    let seen: serde_json::Value =
        serde_json::from_str(&last).unwrap_or_else(|e| panic!("{e}: {last}"));
    eprintln!("browser saw: {seen}");
    seen
}
