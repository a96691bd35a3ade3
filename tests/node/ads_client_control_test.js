// ADS state control and the levels of the HLI's type tree seen by the unmodified Node
// `ads-client` 2.x: with its DEFAULT settings, readTcSystemExtendedState at connect and by
// call, readValue / createVariableHandle of levels between the listed symbols, stopPlc,
// startPlc, resetPlc; then, with a rawClient (no state poller to race), setTcSystemToConfig,
// the extended state in CONFIG, and the restart that setTcSystemToRun sends (WriteControl
// RESET to 10000). Run by tests/ads_clients/ads_node.rs:
//
//   NCCHANNEL_ADS_ADDR=127.0.0.1:48898 node tests/node/ads_client_control_test.js
//
// Prints one JSON line (what it saw); exits non-zero on a failed check.
"use strict";
const { check, serverClient } = require("./common");

const CH = "HLI_Global_Variables.gpCh[0]^";
const MS = CH + ".channel_mc_control.mode_and_state";

function client(raw, localAdsPort) {
  return serverClient(localAdsPort, { rawClient: raw });
}

async function main() {
  const seen = {};
  const plc = client(false, 32911);
  await plc.connect();
  check(plc.metaData.tcSystemState.restartIndex === 0, "extended state read at connect");
  const ext = await plc.readTcSystemExtendedState();
  seen.extended = [ext.adsStateStr, ext.restartIndex, ext.version, ext.revision, ext.build];

  // Levels between the listed symbols.
  const kopf = (await plc.readValue(CH + ".mc_error.satz_r.kopf")).value;
  check(kopf && typeof kopf.error_id === "number", "kopf as a struct: " + JSON.stringify(kopf));
  seen.kopf_fields = Object.keys(kopf).length;
  const unit = (await plc.readValue(MS)).value;
  seen.mode_and_state = [unit.length, unit[0], unit[4]];
  for (const name of [CH, "HLI_Global_Variables"]) {
    const h = await plc.createVariableHandle(name);
    check(h.size > 0, name + ": " + JSON.stringify(h));
    await plc.deleteVariableHandle(h);
  }

  // The PLC runtime: stop, start, reset (then STOP), start.
  const states = [];
  for (const step of ["stopPlc", "startPlc", "resetPlc", "startPlc"]) {
    await plc[step]();
    states.push((await plc.readPlcRuntimeState()).adsStateStr);
  }
  seen.plc_states = states;
  await plc.disconnect();

  // The system service: CONFIG, then the restart.
  const raw = client(true, 32912);
  await raw.connect();
  await raw.setTcSystemToConfig();
  const config = await raw.readTcSystemExtendedState();
  let plcInConfig = "reachable";
  try {
    await raw.readPlcRuntimeState();
  } catch (e) {
    plcInConfig = e.adsError ? e.adsError.errorCode : String(e.message);
  }
  await raw.writeControl("Reset", 0, undefined, { adsPort: 10000 });
  const restarted = await raw.readTcSystemExtendedState();
  seen.system = [config.adsStateStr, plcInConfig, restarted.adsStateStr, restarted.restartIndex];
  seen.plc_after_restart = (await raw.readPlcRuntimeState()).adsStateStr;
  await raw.disconnect();
  console.log(JSON.stringify(seen));
}

main().catch((e) => {
  console.error("FAILED: " + (e && e.stack ? e.stack : e));
  process.exit(1);
});
