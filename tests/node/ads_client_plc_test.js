// ncchannel's PLC runtime (AMS port 851) and TwinCAT system service (10000) seen by the
// unmodified Node `ads-client` 2.x with its DEFAULT settings (not rawClient): connect() reads
// the system state on 10000, device info, upload info, symbol version and subscribes to the
// runtime state and symbol version, as against a TwinCAT PLC. Then getSymbols, readValue of
// HLI structs (data types by name), subscribeValue, writeValue of the mode-and-state command
// unit (starts the streaming program), a read back through a variable handle, and a refused
// command showing up as an error record. Run by tests/ads_clients/ads_node.rs:
//
//   NCCHANNEL_ADS_ADDR=127.0.0.1:48898 node tests/node/ads_client_plc_test.js
//
// Prints one JSON line (what it saw); exits non-zero on a failed check.
"use strict";
const { Client } = require("ads-client");
const { check, sleep } = require("./common");

const [host, port] = process.env.NCCHANNEL_ADS_ADDR.split(":");
const CH = "HLI_Global_Variables.gpCh[0]^";
const MS = CH + ".channel_mc_control.mode_and_state";
const [AUTOMATIC, MDI] = [2, 3];
const [READY, ACTIVE] = [3, 4];

async function waitFor(what, pred) {
  const deadline = Date.now() + 20000;
  for (;;) {
    const v = await pred();
    if (v) return v;
    check(Date.now() < deadline, "timed out waiting for " + what);
    await sleep(10);
  }
}

// Hand command_w to the CNC: writeValue fills the fields not given from the current value.
async function command(client, toMode, toState, parameter) {
  await client.writeValue(MS + ".command_w", { to_mode: toMode, to_state: toState, parameter }, true);
  await client.writeValue(MS + ".command_semaphor_rw", true);
}

async function main() {
  const client = new Client({
    targetAmsNetId: "127.0.0.1.1.1",
    targetAdsPort: 851,
    routerAddress: host,
    routerTcpPort: Number(port),
    localAmsNetId: "10.1.2.3.1.1",
    localAdsPort: 32901,
    autoReconnect: false,
    hideConsoleWarnings: true,
  });
  const seen = {};
  await client.connect();
  const md = client.metaData;
  check(md.tcSystemState && md.tcSystemState.adsState === 5, "system service in RUN");
  check(md.plcRuntimeState === undefined || md.plcRuntimeState.adsState === 5, "PLC in RUN");
  check(md.plcUploadInfo.symbolCount > 0, "upload info");
  check(md.plcSymbolVersion === 1, "symbol version " + md.plcSymbolVersion);
  seen.device = md.plcDeviceInfo.deviceName;
  seen.system_state = (await client.readTcSystemState()).adsStateStr;
  seen.plc_state = (await client.readPlcRuntimeState()).adsStateStr;

  const symbols = await client.getSymbols();
  const names = Object.keys(symbols);
  check(names.length === md.plcUploadInfo.symbolCount, "every uploaded symbol parsed");
  const state = symbols[(MS + ".state_r").toLowerCase()];
  check(state && state.type === "HLI_IMCM_MODE_STATE" && state.size === 8, "state_r listed");
  seen.symbols = names.length;

  // A struct read by name: the data type's members give the object's fields.
  const before = (await client.readValue(MS + ".state_r")).value;
  check(before.mode === AUTOMATIC && before.state === READY, "READY: " + JSON.stringify(before));

  // The state followed by a notification on a struct member.
  const states = [];
  const sub = await client.subscribeValue(MS + ".state_r.state", (d) => states.push(d.value), 10, true);
  await waitFor("the first sample", () => states.length > 0);

  await command(client, AUTOMATIC, ACTIVE, "streaming.nc");
  await waitFor("ACTIVE notified", () => states.includes(ACTIVE));
  // Read back through a handle, and on the COM task's mcm_active_r (port 553).
  const h = await client.createVariableHandle(MS + ".state_r.state");
  check(h.size === 4 && h.dataType === "UDINT", "full handle reply: " + JSON.stringify(h));
  const byHandle = (await client.readRawByHandle(h)).readUInt32LE(0);
  await client.deleteVariableHandle(h);
  const com = (await client.readRaw(0x120101, 0x109, 4, { adsPort: 553 })).readInt32LE(0);
  check(byHandle === ACTIVE && com === ACTIVE, "ACTIVE by handle " + byHandle + ", COM " + com);
  const program = (await client.readValue(MS + ".command_w")).value.parameter;
  check(program === "streaming.nc", "command_w read back: " + program);
  await sub.unsubscribe();
  seen.states = states;

  // Back to READY, then a command the CNC refuses: an MDI block raises error 270061.
  await command(client, 0, 15, "");
  await waitFor("READY", async () => (await client.readValue(MS + ".state_r.state")).value === READY);
  await command(client, MDI, ACTIVE, "G01 X10 F1000");
  const err = await waitFor("error record", async () => {
    const v = (await client.readValue(CH + ".mc_error.semaphor_rw")).value;
    return v && (await client.readValue(CH + ".mc_error.satz_r")).value;
  });
  check(err.kopf.error_id === 270061, "refusal posted: " + JSON.stringify(err.kopf));
  seen.refused = err.kopf.error_id;
  await client.writeValue(CH + ".mc_error.semaphor_rw", false);
  const after = (await client.readValue(MS + ".state_r")).value;
  check(after.mode === AUTOMATIC && after.state === READY, "refused: nothing applied");

  await client.disconnect();
  console.log(JSON.stringify(seen));
}

main().catch((e) => {
  console.error("FAILED: " + (e && e.stack ? e.stack : e));
  process.exit(1);
});
