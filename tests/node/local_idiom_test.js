// ncchannel serve on its default address seen by the unmodified Node `ads-client` 2.x with the
// settings of its README's local example: `targetAmsNetId: 'localhost'` (127.0.0.1.1.1),
// router on localhost:48898, the local AMS address asked of the router (port connect).
// Run by tests/ads_clients/ads_local_idioms.rs. Prints one JSON line.
"use strict";
const { Client } = require("ads-client");
const { check } = require("./common");

async function main() {
  const client = new Client({
    targetAmsNetId: "localhost",
    targetAdsPort: 851,
    autoReconnect: false,
    hideConsoleWarnings: true,
  });
  const res = await client.connect();
  const seen = {
    local: res.localAmsNetId,
    device: client.metaData.plcDeviceInfo.deviceName,
    system_state: (await client.readTcSystemState()).adsStateStr,
  };
  const ms = await client.readValue("HLI_Global_Variables.gpCh[0]^.channel_mc_control.mode_and_state.state_r");
  check(ms.value.state === 3, "READY: " + JSON.stringify(ms.value));
  seen.state = ms.value.state;
  await client.disconnect();
  console.log(JSON.stringify(seen));
}

main().catch((e) => {
  console.error("FAILED: " + (e && e.stack ? e.stack : e));
  process.exit(1);
});
