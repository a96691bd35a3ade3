//! `ncchannel bench --load live-view`: the runtime's tick figures with no page and with pages
//! on the event stream, from one run, and the update rate the pages received.

use std::process::Command;

/// The figure after `key` on the line starting with `prefix`.
fn figure(out: &str, prefix: &str, key: &str) -> f64 {
    let line = out
        .lines()
        .find(|l| l.starts_with(prefix))
        .unwrap_or_else(|| panic!("no line {prefix:?} in\n{out}"));
    let rest = &line[line.find(key).unwrap_or_else(|| panic!("{key} in {line}")) + key.len()..];
    rest.split(|c: char| c.is_whitespace() || c == ';' || c == ')')
        .find(|w| !w.is_empty())
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("{key} in {line}"))
}

#[test]
fn the_live_view_bench_measures_both_phases_and_the_pages_get_their_updates() {
    let out = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args([
            "bench",
            "--load",
            "live-view",
            "--seconds",
            "1",
            "--pages",
            "2",
        ])
        .output()
        .expect("ncchannel bench runs");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // One slice of a second each, at the shipped 1 ms cycle.
    assert_eq!(figure(&text, "no page", "(n ="), 1000.0, "{text}");
    assert_eq!(figure(&text, "pages connected", "(n ="), 1000.0, "{text}");
    assert!(figure(&text, "no page", "tick work p50") > 0.0, "{text}");
    // The feed sends one update per period to each page: never more, and some got through.
    let per_page = figure(&text, "updates received", "=");
    let most = 1.0 / ncchannel::http::FEED_PERIOD.as_secs_f64();
    assert!(per_page > 0.0 && per_page <= most * 1.25, "{text}");
    // The program ran while measured.
    assert!(figure(&text, "ratio", "executed") > 0.0, "{text}");
}
