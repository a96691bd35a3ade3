//! Runs tests/node/ads_client_test.js (the unmodified Node `ads-client` 2.x in rawClient
//! mode) against the real channels: the description table, a 5,000-line stream with 0x708
//! retries, a notification on `mc_block_count_r`. Needs Node and `npm install --prefix
//! tests/node` (done by `.ci/run`), so it is ignored by default:
//!
//! `cargo test --test ads_clients -- --ignored ads_node`

use crate::support as common;

#[test]
#[ignore = "needs Node and tests/node/node_modules: npm install --prefix tests/node"]
fn node_ads_client_streams_5000_lines_and_watches_the_block_count() {
    let node = std::env::var("NCCHANNEL_NODE").unwrap_or_else(|_| "node".into());
    let rig = common::Rig::new();
    let lines = common::streamed_5000_lines();
    let file = rig.dir.path().join("prog.nc");
    std::fs::write(&file, lines.join("\n") + "\n").unwrap();
    let served = common::Served::start(&rig);
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/node/ads_client_test.js");
    let (seen, events) = common::run_client(served, &node, script, &[&file]);
    assert!(
        seen["busy"].as_u64().unwrap() > 0,
        "the client was refused at least once"
    );
    assert_eq!(seen["final_count"], 5000);
    assert_eq!(common::block_texts(&events), lines);
}

/// The unmodified Node `ads-client` with its DEFAULT settings against the PLC runtime (851):
/// connect() reads the TwinCAT system service on 10000, upload info, symbol version, device
/// info and subscribes the runtime state; then getSymbols, readValue of HLI structs,
/// subscribeValue, writeValue of the mode-and-state unit (the streaming program starts, seen
/// through a handle and on COM), and a refused MDI block raising error 270061 on the HLI.
#[test]
#[ignore = "needs Node and tests/node/node_modules: npm install --prefix tests/node"]
fn node_ads_client_default_connect_reads_and_writes_hli_symbols() {
    let node = std::env::var("NCCHANNEL_NODE").unwrap_or_else(|_| "node".into());
    let rig = common::Rig::new();
    let served = common::Served::start(&rig);
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/node/ads_client_plc_test.js"
    );
    let (seen, events) = common::run_client(served, &node, script, &[]);
    assert_eq!(seen["system_state"], "Run");
    assert_eq!(seen["plc_state"], "Run");
    assert_eq!(seen["device"], "Plc30 App");
    assert!(seen["symbols"].as_u64().unwrap() > 100, "{seen}");
    assert_eq!(seen["refused"], 270061);
    let states = seen["states"].as_array().unwrap();
    assert_eq!(states.first(), Some(&serde_json::json!(3)), "READY first");
    assert!(states.contains(&serde_json::json!(4)), "then ACTIVE");
    let started = common::of(&events, "state")
        .iter()
        .any(|e| e["state"] == "ACTIVE");
    assert!(started, "the channel ran the streaming program");
}

/// The unmodified Node `ads-client`: `readTcSystemExtendedState`, `readValue` and
/// `createVariableHandle` of levels between the listed HLI symbols, `stopPlc`, `startPlc`,
/// `resetPlc`, `setTcSystemToConfig` and the restart (WriteControl RESET to 10000).
#[test]
#[ignore = "needs Node and tests/node/node_modules: npm install --prefix tests/node"]
fn node_ads_client_controls_the_ads_states_and_reads_every_symbol_level() {
    let node = std::env::var("NCCHANNEL_NODE").unwrap_or_else(|_| "node".into());
    let rig = common::Rig::new();
    let served = common::Served::start(&rig);
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/node/ads_client_control_test.js"
    );
    let (seen, _events) = common::run_client(served, &node, script, &[]);
    assert_eq!(seen["extended"], serde_json::json!(["Run", 0, 3, 1, 4024]));
    assert_eq!(seen["kopf_fields"], 21, "HLI_ERROR_SATZ_KOPF's members");
    assert_eq!(seen["mode_and_state"], serde_json::json!([665, 2, 3]));
    assert_eq!(
        seen["plc_states"],
        serde_json::json!(["Stop", "Run", "Stop", "Run"])
    );
    assert_eq!(
        seen["system"],
        serde_json::json!(["Config", 6, "Run", 1]),
        "{seen}"
    );
    assert_eq!(seen["plc_after_restart"], "Run");
}

#[test]
#[ignore = "needs Node and tests/node/node_modules: npm install --prefix tests/node"]
fn node_ten_hmis_connect_beside_one_heavy_subscriber() {
    let node = std::env::var("NCCHANNEL_NODE").unwrap_or_else(|_| "node".into());
    let rig = common::Rig::new();
    let served = common::Served::start(&rig);
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/node/many_hmis_test.js");
    let (seen, _) = common::run_client(served, &node, script, &[]);
    println!("MANY HMIS {seen}");
    assert_eq!(
        seen["heavy_handles"], 10,
        "ten 1 ms handles on one connection"
    );
    assert_eq!(
        seen["hmis_connected"], 10,
        "ten default connect()s beside it"
    );
    assert_eq!(
        seen["hmi_samples"], 10,
        "each HMI's own subscription samples"
    );
    assert_eq!(
        seen["heavy_eleventh"], 0x716,
        "the heavy client's eleventh 1 ms handle is refused to it"
    );
}

/// ads-client 1 ms subscriptions counted against the tick counter: an on-change one on COM's
/// `cnc_tick_counter_r` and a cyclic one on GEO's tick counter each see 500 consecutive ticks.
#[test]
#[ignore = "needs Node and tests/node/node_modules: npm install --prefix tests/node"]
fn node_1_ms_subscriptions_see_every_tick() {
    let node = std::env::var("NCCHANNEL_NODE").unwrap_or_else(|_| "node".into());
    let rig = common::Rig::new();
    let served = common::Served::start(&rig);
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/node/tick_notifications_test.js"
    );
    let (seen, _) = common::run_client(served, &node, script, &[]);
    assert_eq!(seen["on_change"], serde_json::json!([500, 499]), "{seen}");
    assert_eq!(seen["cyclic"], serde_json::json!([500, 499]), "{seen}");
}
