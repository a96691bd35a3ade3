// 1 ms notifications counted against the tick counter with the unmodified Node `ads-client`
// 2.x: an on-change subscription to the COM task's `cnc_tick_counter_r` (port 553) and a cyclic
// one to the GEO task's tick counter (port 551), both at a 1 ms cycle while the channels tick
// every 1 ms. Each must see every tick: consecutive samples one apart over 500 samples. Run by
// tests/ads_clients/ads_node.rs:
//
//   NCCHANNEL_ADS_ADDR=127.0.0.1:48898 node tests/node/tick_notifications_test.js
//
// Prints one JSON line (what it saw); exits non-zero on a failed check.
"use strict";
const { check, sleep, serverClient } = require("./common");

const COM_TICK_COUNTER = { indexGroup: 0x120101, indexOffset: 0x251, size: 4 };
const GEO_TICK_COUNTER = { indexGroup: 0x120300, indexOffset: 0x07, size: 4 };
const SAMPLES = 500;

const gaps = (v) => v.slice(1).map((b, i) => [v[i], b]).filter(([a, b]) => b !== a + 1);

async function main() {
  const client = serverClient(33200, { targetAdsPort: 553, rawClient: true, timeoutDelay: 5000 });
  await client.connect();
  const onChange = [];
  const cyclic = [];
  const sample = (into) => (data) => into.push(data.value.readUInt32LE(0));
  const subs = [
    await client.subscribe({
      target: COM_TICK_COUNTER,
      callback: sample(onChange),
      cycleTime: 1,
      sendOnChange: true,
    }),
    await client.subscribe(
      { target: GEO_TICK_COUNTER, callback: sample(cyclic), cycleTime: 1, sendOnChange: false },
      { adsPort: 551 }
    ),
  ];
  for (let waited = 0; onChange.length < SAMPLES || cyclic.length < SAMPLES; waited += 10) {
    check(waited < 20000, `500 samples of each within 20 s: ${onChange.length}, ${cyclic.length}`);
    await sleep(10);
  }
  for (const s of subs) await s.unsubscribe();
  await client.disconnect();
  const seenChange = onChange.slice(0, SAMPLES);
  const seenCyclic = cyclic.slice(0, SAMPLES);
  check(gaps(seenChange).length === 0,
    "the 1 ms on-change subscription saw every tick: " + JSON.stringify(gaps(seenChange).slice(0, 10)));
  check(gaps(seenCyclic).length === 0,
    "the 1 ms cyclic subscription sampled every cycle: " + JSON.stringify(gaps(seenCyclic).slice(0, 10)));
  console.log(JSON.stringify({
    on_change: [seenChange.length, seenChange[SAMPLES - 1] - seenChange[0]],
    cyclic: [seenCyclic.length, seenCyclic[SAMPLES - 1] - seenCyclic[0]],
  }));
}

main().catch((e) => {
  console.error("FAILED: " + (e && e.stack ? e.stack : e));
  process.exit(1);
});
