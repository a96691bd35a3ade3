// The unmodified Node `ads-client` 2.x with its default request timeout (2 s) streams a program
// while the runtime stalls for longer than that: every write must be answered (0 or 0x708,
// never a timeout), and the client retries 0x708 as the streaming interface prescribes. Run
// by tests/ads_clients/ads_node_stall.rs:
//
//   NCCHANNEL_ADS_ADDR=127.0.0.1:48898 node tests/node/stream_through_a_stall.js PROGRAM_FILE
//
// Prints one JSON line (what it saw); exits non-zero on a failed check.
"use strict";
const fs = require("fs");
const { Client } = require("ads-client");
const { check, sleep, packets } = require("./common");

const [host, port] = process.env.NCCHANNEL_ADS_ADDR.split(":");
const CH = 0x120101;
const BUSY = 0x708;

async function main() {
  // Nothing about timeouts is set: ads-client's default timeoutDelay (2000 ms) applies.
  const client = new Client({
    targetAmsNetId: "127.0.0.2.1.1",
    targetAdsPort: 553,
    routerAddress: host,
    routerTcpPort: Number(port),
    localAmsNetId: "10.1.2.3.1.1",
    localAdsPort: 32901,
    rawClient: true,
    autoReconnect: false,
    hideConsoleWarnings: true,
  });
  await client.connect();
  const i32 = (v) => { const b = Buffer.alloc(4); b.writeInt32LE(v); return b; };
  await client.writeRaw(CH, 0x104, i32(2));
  await client.writeRaw(CH, 0x108, Buffer.from("streaming.nc\0", "latin1"));
  await client.writeRaw(CH, 0x105, i32(4));

  const lines = fs.readFileSync(process.argv[2], "latin1").split("\n").filter((l) => l.length > 0);
  const seen = { busy: 0, slow_busy: 0, max_answer_ms: 0 };
  for (const p of packets(lines)) {
    for (;;) {
      const asked = Date.now();
      try {
        await client.writeRaw(CH, 0x90, Buffer.from(p, "latin1"));
        seen.max_answer_ms = Math.max(seen.max_answer_ms, Date.now() - asked);
        break;
      } catch (e) {
        const took = Date.now() - asked;
        seen.max_answer_ms = Math.max(seen.max_answer_ms, took);
        const code = e.adsError && e.adsError.errorCode;
        check(code === BUSY, "stream write answered " + code + " after " + took + " ms: " + e.message);
        seen.busy += 1;
        // A "busy" that took this long came from the stalled runtime, not a full stream.
        if (took >= 300) seen.slow_busy += 1;
        await sleep(1);
      }
    }
  }
  // Wait for the program end (mcm_active_state_r READY).
  const deadline = Date.now() + 60000;
  for (;;) {
    const state = (await client.readRaw(CH, 0x109, 4)).readInt32LE(0);
    if (state === 3) break;
    check(state === 4, "state " + state + " while streaming");
    check(Date.now() < deadline, "program end within 60 s");
    await sleep(20);
  }
  await client.disconnect();
  console.log(JSON.stringify(seen));
}

main().catch((e) => {
  console.error("FAILED: " + (e && e.stack ? e.stack : e));
  process.exit(1);
});
