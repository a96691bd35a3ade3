// Many HMIs beside one heavy subscriber, with the unmodified Node `ads-client` 2.x: one client
// (rawClient) holds ten 1 ms on-change handles on the COM block counter, then ten clients with
// the DEFAULT settings connect() at once (each subscribes to the runtime state and the symbol
// version, as against a TwinCAT PLC) and each subscribes a 100 ms value; an eleventh 1 ms
// handle of the heavy client is refused 0x716 to it alone. Run by
// tests/ads_clients/ads_node.rs:
//
//   NCCHANNEL_ADS_ADDR=127.0.0.1:48898 node tests/node/many_hmis_test.js
//
// Prints one JSON line (what it saw); exits non-zero on a failed check.
"use strict";
const { check, serverClient } = require("./common");

const CH = 0x120101;
const BLOCK_COUNTER = 0x8002;
const MS = "HLI_Global_Variables.gpCh[0]^.channel_mc_control.mode_and_state.state_r";

function client(localAdsPort, extra) {
  return serverClient(localAdsPort, { timeoutDelay: 5000, ...extra });
}

async function main() {
  const seen = {};
  const heavy = client(33000, { targetAdsPort: 553, rawClient: true });
  await heavy.connect();
  const subscribe1ms = () =>
    heavy.subscribe({
      target: { indexGroup: CH, indexOffset: BLOCK_COUNTER, size: 8 },
      callback: () => {},
      cycleTime: 1,
      sendOnChange: true,
    });
  const heavySubs = [];
  for (let i = 0; i < 10; i++) heavySubs.push(await subscribe1ms());
  seen.heavy_handles = heavySubs.length;

  const hmis = Array.from({ length: 10 }, (_, i) => client(33100 + i, {}));
  await Promise.all(hmis.map((c) => c.connect()));
  seen.hmis_connected = hmis.length;
  const values = await Promise.all(
    hmis.map(
      (c) =>
        new Promise((resolve, reject) => {
          c.subscribeValue(MS, (d) => resolve(d.value), 100).catch(reject);
        })
    )
  );
  check(values.every((v) => v && v.mode !== undefined), "every HMI got its first sample");
  seen.hmi_samples = values.length;

  let refused = null;
  try {
    await subscribe1ms();
  } catch (e) {
    refused = e.adsError ? e.adsError.errorCode : String(e);
  }
  seen.heavy_eleventh = refused;

  await Promise.all(hmis.map((c) => c.disconnect()));
  await heavy.disconnect();
  console.log(JSON.stringify(seen));
}

main().catch((e) => {
  console.error("FAILED: " + (e && e.stack ? e.stack : e));
  process.exit(1);
});
