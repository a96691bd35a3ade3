// The unmodified Node `ads-client` 2.x (default settings) as the PLC of a channel's technology
// units on AMS port 851 (TF5200 HLI "Technology functions", "Data of the M/H function"; the
// PLC side as kimblad/TwinSharp TwinSharp/CNC/TechnologyProcesses.cs runs it). M25 is MVS_SVS
// in the channel's table and `techno.nc` is N10 G01 X10 F6000 / N20 X20 M25 / N30 X30 / M30.
// The client sets head.plc_present_w, starts the program through the mode-and-state command
// unit, subscribes to techno_unit_std_sync by name (the array of TECHNO_UNIT_CH structs is
// parsed from the served data types), reads used_units_std_sync_r and the unit, holds the
// acknowledgement for 200 ms, then writes please_rw FALSE and done_w TRUE. Run by
// tests/ads_clients/ads_techno_clients.rs:
//
//   NCCHANNEL_ADS_ADDR=127.0.0.1:48898 node tests/node/techno_plc_test.js
//
// Prints one JSON line (what it saw); exits non-zero on a failed check.
"use strict";
const { Client } = require("ads-client");
const { check, sleep } = require("./common");

const [host, port] = process.env.NCCHANNEL_ADS_ADDR.split(":");
const CH = "HLI_Global_Variables.gpCh[0]^";
const MS = CH + ".channel_mc_control.mode_and_state";
const [AUTOMATIC, READY, ACTIVE] = [2, 3, 4];

async function waitFor(what, pred) {
  const deadline = Date.now() + 20000;
  for (;;) {
    const v = await pred();
    if (v) return v;
    check(Date.now() < deadline, "timed out waiting for " + what);
    await sleep(5);
  }
}

// TECHNO_UNIT_CH as ads-client parses it: please_rw, done_w, type, fill_up_1, attribut_r.data
// (39 bytes, HLI_M_H_PROZESS in the first 32).
function decode(u) {
  const d = Buffer.from(u.attribut_r.data);
  return {
    please: u.please_rw ? 1 : 0,
    done: u.done_w ? 1 : 0,
    type: u.type,
    nr: d.readUInt32LE(0),
    time: d.readInt32LE(4),
    block_nr: d.readUInt32LE(8),
    prg_line: d.readUInt32LE(12),
    add_value: d.readInt32LE(16),
    synch_mode: d.readUInt32LE(24),
  };
}

async function main() {
  const client = new Client({
    targetAmsNetId: "127.0.0.1.1.1",
    targetAdsPort: 851,
    routerAddress: host,
    routerTcpPort: Number(port),
    localAmsNetId: "10.1.2.3.1.1",
    localAdsPort: 32911,
    autoReconnect: false,
    hideConsoleWarnings: true,
  });
  const seen = {};
  await client.connect();
  await client.writeValue(CH + ".head.plc_present_w", true);
  check((await client.readValue(CH + ".head.plc_present_w")).value === true, "plc_present_w");

  const asking = [];
  const sub = await client.subscribeValue(
    CH + ".techno_unit_std_sync",
    (d) => {
      if (d.value[0].please_rw) asking.push(decode(d.value[0]));
    },
    25,
    true,
  );

  await client.writeValue(MS + ".command_w", { to_mode: AUTOMATIC, to_state: ACTIVE, parameter: "techno.nc" }, true);
  await client.writeValue(MS + ".command_semaphor_rw", true);
  await waitFor("a notification with a unit asking", () => asking.length > 0);
  seen.notified = asking[0];
  const used = (await client.readValue(CH + ".used_units_std_sync_r")).value;
  check(used === 1, "one unit to acknowledge: " + used);
  seen.unit = decode((await client.readValue(CH + ".techno_unit_std_sync[0]")).value);

  // Hold the acknowledgement: the channel waits for it (MVS_SVS).
  await sleep(200);
  check((await client.readValue(MS + ".state_r.state")).value === ACTIVE, "still ACTIVE while the M waits");
  await client.writeValue(CH + ".techno_unit_std_sync[0].please_rw", false);
  await client.writeValue(CH + ".techno_unit_std_sync[0].done_w", true);
  await waitFor("program end", async () => (await client.readValue(MS + ".state_r.state")).value === READY);
  seen.used_after = (await client.readValue(CH + ".used_units_std_sync_r")).value;
  await sub.unsubscribe();
  await client.disconnect();
  console.log(JSON.stringify(seen));
}

main().catch((e) => {
  console.error("FAILED: " + (e && e.stack ? e.stack : e));
  process.exit(1);
});
