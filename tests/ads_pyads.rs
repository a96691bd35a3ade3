//! Runs tests/python/test_pyads.py (unmodified pyads 3.6 + adslib) against the server over the
//! in-memory backend. Needs a Python with pyads, so it is ignored by default:
//!
//! `NCCHANNEL_PYTHON=/path/to/venv/bin/python cargo test --test ads_pyads -- --ignored`

mod ads_common;

use std::process::Command;

#[test]
#[ignore = "needs Python with pyads: NCCHANNEL_PYTHON=… cargo test --test ads_pyads -- --ignored"]
fn pyads_talks_to_the_server() {
    let python = std::env::var("NCCHANNEL_PYTHON").unwrap_or_else(|_| "python3".into());
    let (srv, _backend) = ads_common::server();
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/python/test_pyads.py");
    let out = Command::new(python)
        .arg(script)
        .env("NCCHANNEL_ADS_ADDR", srv.local_addr().to_string())
        .output()
        .expect("python runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(!stderr.contains("skipped"), "{stderr}");
}
