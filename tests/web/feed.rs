//! The page and its event stream over real sockets: embedded assets, positions that move, the
//! executing line, errors as they are raised, and the cap on connected pages.

use std::time::{Duration, Instant};

use ncchannel::http::{ControlAccess, MAX_PAGE_CONNECTIONS};
use ncchannel::machine::Op;
use ncchannel::vocab::mode::State;

use super::client::{self, Events};
use super::view;

const WITHIN: Duration = Duration::from_secs(20);

#[test]
fn the_page_is_embedded_and_loads_nothing_from_elsewhere() {
    let (web, _channels) = view(ControlAccess::Refused);
    let addr = web.local_addr();
    let page = client::get(addr, "/");
    assert_eq!(page.status, 200);
    assert!(page
        .header("content-type")
        .unwrap()
        .starts_with("text/html"));
    let csp = page.header("content-security-policy").unwrap();
    assert!(csp.contains("default-src 'self'"), "{csp}");
    assert!(page.body.contains("/app.js") && page.body.contains("/style.css"));
    for path in ["/", "/app.js", "/style.css"] {
        let r = client::get(addr, path);
        assert_eq!(r.status, 200, "{path}");
        assert!(
            !r.body.contains("http://") && !r.body.contains("https://"),
            "{path} refers to another site"
        );
    }
    assert_eq!(client::get(addr, "/nothing-here").status, 404);
}

#[test]
fn updates_carry_moving_positions_and_the_executing_line() {
    let (web, channels) = view(ControlAccess::Refused);
    channels.command(1, Op::Start("square.nc".into()));
    let mut events = Events::open(web.local_addr());
    assert_eq!(events.status, 200);
    let listing = events.until(WITHIN, |name, d| {
        (name == "listing" && d["ch"] == 1 && d["lines"].as_array()?.len() > 2).then(|| d.clone())
    });
    assert_eq!(listing["program"], "square.nc");
    assert_eq!(listing["lines"][2], "N20 G01 X40 Y0");
    // Two updates while N20 runs (line 3), X further along in the second.
    let mut xs = Vec::new();
    events.until(WITHIN, |name, d| {
        let c = client::channel(d, 1).filter(|_| name == "status")?;
        if c["line"] == 3 && c["state"] == "ACTIVE" {
            xs.push(client::axis(c, "X"));
            assert!(c["distance_to_go_mm"].as_f64().unwrap() >= 0.0);
        }
        (xs.len() >= 2 && xs[xs.len() - 1] > xs[0]).then_some(())
    });
    assert!(xs.iter().all(|x| (0.0..=40.0).contains(x)), "{xs:?}");
}

#[test]
fn an_error_raised_on_a_stream_line_reaches_the_page() {
    let (web, channels) = view(ControlAccess::Refused);
    channels.command(2, Op::Start("streaming.nc".into()));
    let mut events = Events::open(web.local_addr());
    // The page is watching before the bad line arrives.
    events.until(WITHIN, |name, d| {
        (name == "status" && client::channel(d, 2)?["state"] == "ACTIVE").then_some(())
    });
    let reply = channels
        .backend
        .call(2, Op::WriteStream(b"N10 G01 X1 Y=\r\n"[..].into()));
    assert!(reply.is_ok(), "{reply:?}");
    let error = events.until(WITHIN, |name, d| {
        (name == "nc-error" && d["ch"] == 2).then(|| d.clone())
    });
    assert_eq!(error["index"], 0);
    let code = error["code"].as_u64().unwrap();
    assert!(
        (20_000..30_000).contains(&code),
        "an NC error number: {error}"
    );
    assert!(!error["text"].as_str().unwrap().is_empty());
    assert_eq!(channels.status(2).state, State::Error);
}

#[test]
fn connected_pages_are_capped_and_a_closed_one_frees_its_place() {
    let (web, _channels) = view(ControlAccess::Refused);
    let addr = web.local_addr();
    let mut open: Vec<Events> = (0..MAX_PAGE_CONNECTIONS)
        .map(|_| Events::open(addr))
        .collect();
    assert!(open.iter().all(|e| e.status == 200));
    let refused = client::get(addr, "/events");
    assert_eq!(refused.status, 503);
    assert!(
        refused.body.contains("connected already"),
        "{}",
        refused.body
    );
    // The page and its controls still load while the streams are full.
    assert_eq!(client::get(addr, "/").status, 200);
    drop(open.pop());
    let deadline = Instant::now() + WITHIN;
    loop {
        let again = Events::open(addr);
        if again.status == 200 {
            break;
        }
        assert!(
            Instant::now() < deadline,
            "the closed page's place was not freed"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// A page that connects while the square runs gets its whole path since the start (its
/// corner at X40 Y0 included), and `GET /snapshot.json` answers the executing block's F.
#[test]
fn a_late_page_gets_the_path_since_the_start_and_scripts_a_snapshot() {
    let (web, channels) = view(ControlAccess::Refused);
    let addr = web.local_addr();
    channels.command(1, Op::Start("square.nc".into()));
    let mut first = Events::open(addr);
    // The arc N30 (line 4) runs: the corner at X40 Y0 is behind.
    first.until(WITHIN, |name, d| {
        let c = client::channel(d, 1).filter(|_| name == "status")?;
        (c["line"] == 4).then_some(())
    });
    let late = Events::open(addr).until(WITHIN, |name, d| {
        (name == "path" && d["ch"] == 1).then(|| d.clone())
    });
    assert_eq!(late["reset"], true, "a new page gets the whole path");
    let points: Vec<(f64, f64)> = late["points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| (p[0].as_f64().unwrap(), p[1].as_f64().unwrap()))
        .collect();
    // The drawn path passes within the record's tolerance of the start and of the corner.
    let near = |x: f64, y: f64| {
        points.windows(2).any(|w| {
            let ((ax, ay), (bx, by)) = (w[0], w[1]);
            let (dx, dy) = (bx - ax, by - ay);
            let t = (((x - ax) * dx + (y - ay) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
            (ax + t * dx - x).hypot(ay + t * dy - y) < 0.02
        })
    };
    assert!(near(0.0, 0.0) && near(40.0, 0.0), "{points:?}");
    let snapshot = client::get(addr, "/snapshot.json");
    assert_eq!(snapshot.status, 200);
    assert!(snapshot
        .header("content-type")
        .unwrap()
        .starts_with("application/json"));
    let s: serde_json::Value = serde_json::from_str(&snapshot.body).unwrap();
    let c = client::channel(&s, 1).unwrap();
    assert_eq!(c["program"], "square.nc");
    assert_eq!(c["executing_feed_mm_per_min"], 600.0, "{c}");
    assert!(c["elapsed_s"].as_f64().unwrap() > 0.0, "{c}");
    let g: Vec<&str> = c["g_codes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert!(g.contains(&"G90") && g.contains(&"G17"), "{g:?}");
}

/// The whole-program preview of a file program before it runs: the square's corners, its
/// channel time, and nothing started on the channel.
#[test]
fn a_file_program_is_previewed_before_it_runs() {
    let (web, channels) = view(ControlAccess::Refused);
    let r = client::get(web.local_addr(), "/preview/1/square.nc");
    assert_eq!(r.status, 200, "{}", r.body);
    let p: serde_json::Value = serde_json::from_str(&r.body).unwrap();
    assert_eq!(p["complete"], true, "{p}");
    // 40 + 10 + 30 + 50 + 40 mm and a quarter circle at 10 mm/s: about 17 s.
    let seconds = p["seconds"].as_f64().unwrap();
    assert!((15.0..20.0).contains(&seconds), "{seconds}");
    let points = p["points"].as_array().unwrap();
    let xs: Vec<f64> = points.iter().map(|q| q[0].as_f64().unwrap()).collect();
    let ys: Vec<f64> = points.iter().map(|q| q[1].as_f64().unwrap()).collect();
    let max = |v: &[f64]| v.iter().copied().fold(f64::MIN, f64::max);
    assert!(
        (max(&xs) - 50.0).abs() < 0.05 && (max(&ys) - 40.0).abs() < 0.05,
        "{p}"
    );
    assert_eq!(
        channels.status(1).state,
        State::Ready,
        "the channel itself ran nothing"
    );
    let missing = client::get(web.local_addr(), "/preview/1/nothing.nc");
    assert_eq!(missing.status, 409, "{}", missing.body);
}
