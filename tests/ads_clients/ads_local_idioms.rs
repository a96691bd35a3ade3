//! Each client's own getting-started call against `ncchannel serve` on its default addresses
//! (TCP 127.0.0.1:48898, route service UDP 127.0.0.1:48899, NetId 127.0.0.2.1.1): pyads'
//! `add_route_to_plc` and `Connection('127.0.0.1.1.1', 851)` (tests/python/
//! local_idioms_with_pyads.py), Node ads-client with `targetAmsNetId: 'localhost'`
//! (tests/node/local_idiom_test.js). The clients' idioms name no port, so these tests need the
//! default ports free; they take turns. Ignored by default (`.ci/run` runs them):
//!
//! `NCCHANNEL_PYTHON=… cargo test --test ads_clients -- --ignored ads_local_idioms`

use std::process::{Child, Command, Stdio};
use std::sync::Mutex;

use crate::support as common;

/// One default-address `serve` at a time.
static DEFAULT_PORTS: Mutex<()> = Mutex::new(());

/// `ncchannel serve` on its default addresses over the rig's lists; stopped on drop.
struct DefaultServe {
    child: Child,
}

impl DefaultServe {
    fn start(rig: &common::Rig) -> DefaultServe {
        let mut child = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
            .args(["serve", "--seconds", "120", "--params"])
            .arg(rig.startup())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("ncchannel serve starts");
        let (first, _rest) = common::abuse::collect(child.stderr.take().expect("stderr"));
        assert!(
            common::abuse::unstamped(&first).starts_with(
                "listening on 127.0.0.1:48898 (AMS NetId 127.0.0.2.1.1, port 553, also as \
                 127.0.0.1.1.1, route service UDP 127.0.0.1:48899,"
            ),
            "the default ports must be free: {first}"
        );
        DefaultServe { child }
    }
}

impl Drop for DefaultServe {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn client_json(program: &str, script: &str) -> serde_json::Value {
    let out = Command::new(program)
        .arg(script)
        .output()
        .unwrap_or_else(|e| panic!("{program} runs: {e}"));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(String::from_utf8_lossy(&out.stdout).trim()).unwrap()
}

#[test]
#[ignore = "needs Python with pyads and the default ADS ports: NCCHANNEL_PYTHON=… cargo test --test ads_clients -- --ignored ads_local_idioms"]
fn pyads_add_route_and_connection_to_127_0_0_1_1_1() {
    let _turn = DEFAULT_PORTS.lock().unwrap_or_else(|p| p.into_inner());
    let python = std::env::var("NCCHANNEL_PYTHON").unwrap_or_else(|_| "python3".into());
    let rig = common::Rig::new();
    let _serve = DefaultServe::start(&rig);
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/python/local_idioms_with_pyads.py"
    );
    let seen = client_json(&python, script);
    assert_eq!(seen["route_added"], true);
    assert_eq!(seen["net_id"], "127.0.0.2.1.1");
    assert_eq!(seen["device"], "Plc30 App");
    assert_eq!(seen["state"], serde_json::json!([5, 0]));
    assert_eq!(seen["device_by_own_net_id"], "Plc30 App");
}

#[test]
#[ignore = "needs Node, tests/node/node_modules and the default ADS ports: cargo test --test ads_clients -- --ignored ads_local_idioms"]
fn node_ads_client_with_target_localhost() {
    let _turn = DEFAULT_PORTS.lock().unwrap_or_else(|p| p.into_inner());
    let node = std::env::var("NCCHANNEL_NODE").unwrap_or_else(|_| "node".into());
    let rig = common::Rig::new();
    let _serve = DefaultServe::start(&rig);
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/node/local_idiom_test.js"
    );
    let seen = client_json(&node, script);
    assert_eq!(
        seen["local"], "127.0.0.1.1.1",
        "the router's loopback NetId"
    );
    assert_eq!(seen["device"], "Plc30 App");
    assert_eq!(seen["system_state"], "Run");
    assert_eq!(seen["state"], 3);
}
