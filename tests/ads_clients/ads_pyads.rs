//! Runs tests/python/test_pyads.py (unmodified pyads 3.6 + adslib) against the server over
//! real channels (tests/ads_common). Needs a Python with pyads, so it is ignored by default:
//!
//! `NCCHANNEL_PYTHON=/path/to/venv/bin/python cargo test --test ads_clients -- --ignored ads_pyads`

use crate::support as common;
use crate::support::ads as ads_common;

use std::process::Command;

#[test]
#[ignore = "needs Python with pyads: NCCHANNEL_PYTHON=… cargo test --test ads_clients -- --ignored ads_pyads"]
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

/// A streaming client written with pyads drives the real channels at 1 ms: 5,000 lines,
/// retries on 0x708, every block executed exactly once and in order.
#[test]
#[ignore = "needs Python with pyads: NCCHANNEL_PYTHON=… cargo test --test ads_clients -- --ignored ads_pyads"]
fn pyads_streams_5000_lines_into_real_channels() {
    let python = std::env::var("NCCHANNEL_PYTHON").unwrap_or_else(|_| "python3".into());
    let rig = common::Rig::new();
    let lines = common::streamed_5000_lines();
    let file = rig.dir.path().join("prog.nc");
    std::fs::write(&file, lines.join("\n") + "\n").unwrap();
    let served = common::Served::start(&rig);
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/python/stream_with_pyads.py"
    );
    let out = Command::new(python)
        .arg(script)
        .arg(&file)
        .env("NCCHANNEL_ADS_ADDR", served.server.local_addr().to_string())
        .output()
        .expect("python runs");
    let (_, events) = served.finish();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let counts: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
    let busy = counts["busy"].as_u64().unwrap();
    assert!(
        busy > 0,
        "the pyads client outran the channel at least once"
    );
    let notes = counts["notifications"].as_array().unwrap();
    assert!(
        notes.iter().any(|n| n[1] == 4),
        "a notification reported ACTIVE: {notes:?}"
    );
    assert_eq!(common::block_texts(&events), lines);
    assert_eq!(ads_common::refusals(&events, 11012), busy);
}

/// The PLC's HLI (port 851) with pyads `read_by_name`/`write_by_name`/notifications by name
/// against the real channels: the mode-and-state unit starts the streaming program, a stream
/// runs, `state_r` follows; override at COM 0x09 halves the interpolator's path velocity
/// (GEO 551); NC errors reach `mc_error.satz_r` with their ISG numbers, one at a time.
#[test]
#[ignore = "needs Python with pyads: NCCHANNEL_PYTHON=… cargo test --test ads_clients -- --ignored ads_pyads"]
fn pyads_drives_the_hli_unit_and_reads_geo() {
    let python = std::env::var("NCCHANNEL_PYTHON").unwrap_or_else(|_| "python3".into());
    let rig = common::Rig::new();
    let served = common::Served::start(&rig);
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/python/hli_with_pyads.py"
    );
    let (seen, events) = common::run_client(served, &python, script, &[]);
    assert_eq!(seen["errors"][0], 21476);
    let codes: Vec<_> = common::of(&events, "error")
        .iter()
        .map(|e| e["code"].clone())
        .collect();
    assert_eq!(
        codes,
        [seen["errors"][0].clone(), seen["errors"][1].clone()]
    );
}

/// pyads against the PLC runtime and the TwinCAT system service: `read_state()` on 10000,
/// `get_all_symbols`, `read_list_by_name` and `write_list_by_name` (sum commands); one sum
/// write starts the streaming program through the HLI command unit.
#[test]
#[ignore = "needs Python with pyads: NCCHANNEL_PYTHON=… cargo test --test ads_clients -- --ignored ads_pyads"]
fn pyads_reads_symbols_and_drives_the_hli_by_sum_commands() {
    let python = std::env::var("NCCHANNEL_PYTHON").unwrap_or_else(|_| "python3".into());
    let rig = common::Rig::new();
    let served = common::Served::start(&rig);
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/python/symbols_with_pyads.py"
    );
    let (seen, events) = common::run_client(served, &python, script, &[]);
    assert_eq!(seen["system_state"][0], 5);
    assert_eq!(seen["system_device"], "TwinCAT System");
    assert!(seen["symbols"].as_u64().unwrap() > 100, "{seen}");
    assert_eq!(seen["write_results"], serde_json::json!(["no error"]));
    assert_eq!(seen["state_after"], 4);
    let starts = common::of(&events, "program_start");
    assert_eq!(starts.len(), 1, "started once: {starts:?}");
    assert_eq!(starts[0]["prog"], "streaming.nc");
}

/// pyads `write_control` / `read_state` on 851, 553 and 10000, levels of the HLI's type tree
/// by `get_symbol` / `get_handle` / `read_by_name`, and a start in ERROR answered 0x707.
#[test]
#[ignore = "needs Python with pyads: NCCHANNEL_PYTHON=… cargo test --test ads_clients -- --ignored ads_pyads"]
fn pyads_controls_the_ads_states_and_reaches_every_symbol_level() {
    let python = std::env::var("NCCHANNEL_PYTHON").unwrap_or_else(|_| "python3".into());
    let rig = common::Rig::new();
    let served = common::Served::start(&rig);
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/python/control_with_pyads.py"
    );
    let (seen, _events) = common::run_client(served, &python, script, &[]);
    assert_eq!(
        seen["kopf"],
        serde_json::json!(["HLI_ERROR_SATZ_KOPF", 104])
    );
    assert_eq!(
        seen["mode_and_state"],
        serde_json::json!(["ARRAY [0..664] OF BYTE", 665])
    );
    assert_eq!(
        seen["mode_and_state_head"],
        serde_json::json!([2, 0, 0, 0, 3, 0, 0, 0])
    );
    assert_eq!(seen["gpCh_pointer"], 0x710);
    assert_eq!(seen["write_mode_and_state"], 0x704);
    assert_eq!(seen["plc_states"], serde_json::json!([6, 5, 6]));
    assert_eq!(seen["enable_after_reset"], false);
    assert_eq!(seen["no_line_end"], 0x706);
    assert_eq!(seen["start_in_error"], 0x707);
    assert_eq!(seen["after_cnc_reset"], serde_json::json!([3, 5]));
    assert_eq!(seen["system_config"], 15);
    assert_eq!(seen["plc_in_config"], 6);
    assert_eq!(seen["after_restart"], serde_json::json!([5, 5, 3]));
}

/// pyads 1 ms notifications counted against the tick counter: an on-change handle on COM's
/// `cnc_tick_counter_r` and a cyclic one on GEO's tick counter each see 500 consecutive ticks.
#[test]
#[ignore = "needs Python with pyads: NCCHANNEL_PYTHON=… cargo test --test ads_clients -- --ignored ads_pyads"]
fn pyads_1_ms_notifications_see_every_tick() {
    let python = std::env::var("NCCHANNEL_PYTHON").unwrap_or_else(|_| "python3".into());
    let rig = common::Rig::new();
    let served = common::Served::start(&rig);
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/python/tick_notifications_with_pyads.py"
    );
    let (seen, _events) = common::run_client(served, &python, script, &[]);
    assert_eq!(seen["on_change"], serde_json::json!([500, 499]), "{seen}");
    assert_eq!(seen["cyclic"], serde_json::json!([500, 499]), "{seen}");
}
