// ncchannel's ADS server seen by the unmodified Node `ads-client` 2.x in rawClient mode
// (no PLC symbols): the COM description table, a 5,000-line stream with 0x708 retries, and a
// notification on mc_block_count_r. Run by tests/ads_clients/ads_node.rs:
//
//   NCCHANNEL_ADS_ADDR=127.0.0.1:48898 node tests/node/ads_client_test.js PROGRAM_FILE
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
  const client = new Client({
    targetAmsNetId: "127.0.0.1.1.1",
    targetAdsPort: 553,
    routerAddress: host,
    routerTcpPort: Number(port),
    localAmsNetId: "10.1.2.3.1.1",
    localAdsPort: 32900,
    rawClient: true,
    autoReconnect: false,
    timeoutDelay: 5000,
    hideConsoleWarnings: true,
  });
  await client.connect();
  const seen = {};

  // The description table: count at offset 0, all records in one read at offset 1.
  const count = (await client.readRaw(0x130100, 0, 4)).readUInt32LE(0);
  const table = await client.readRaw(0x130100, 1, count * 84);
  check(table.length === count * 84, "one read returns every record");
  const byName = {};
  for (let i = 0; i < count; i++) {
    const r = table.subarray(i * 84, (i + 1) * 84);
    const name = r.toString("latin1", 20, 52).replace(/\0+$/, "");
    check(!(name in byName), "unique name " + name);
    byName[name] = { size: r.readUInt32LE(4), group: r.readUInt32LE(12), offset: r.readUInt32LE(16) };
  }
  const blockCount = byName["mc_block_count_r"];
  check(blockCount && blockCount.size === 4, "mc_block_count_r listed, 4 bytes");
  seen.objects = count;

  // A notification on mc_block_count_r, on change, checked every 10 ms.
  const counts = [];
  const sub = await client.subscribe({
    target: { indexGroup: blockCount.group, indexOffset: blockCount.offset, size: 4 },
    callback: (data) => counts.push(data.value.readUInt32LE(0)),
    cycleTime: 10,
    sendOnChange: true,
  });

  // Start the streaming program, then stream every line once, retrying 0x708.
  const lines = fs.readFileSync(process.argv[2], "latin1").split("\n").filter((l) => l.length > 0);
  const i32 = (v) => { const b = Buffer.alloc(4); b.writeInt32LE(v); return b; };
  await client.writeRaw(CH, 0x104, i32(2));
  await client.writeRaw(CH, 0x108, Buffer.from("streaming.nc\0", "latin1"));
  await client.writeRaw(CH, 0x105, i32(4));
  let busy = 0;
  for (const p of packets(lines)) {
    for (;;) {
      try {
        await client.writeRaw(CH, 0x90, Buffer.from(p, "latin1"));
        break;
      } catch (e) {
        const code = e.adsError && e.adsError.errorCode;
        check(code === BUSY, "stream write failed: " + e.message);
        busy += 1;
        await sleep(1);
      }
    }
  }
  seen.busy = busy;
  // Wait for the program end (mcm_active_state_r READY).
  const deadline = Date.now() + 60000;
  for (;;) {
    const state = (await client.readRaw(CH, 0x109, 4)).readInt32LE(0);
    if (state === 3) break;
    check(state === 4, "state " + state + " while streaming");
    check(Date.now() < deadline, "program end within 60 s");
    await sleep(20);
  }
  await sleep(100);
  await sub.unsubscribe();
  const final = (await client.readRaw(blockCount.group, blockCount.offset, 4)).readUInt32LE(0);
  check(final === lines.length, "mc_block_count_r = " + final + " lines " + lines.length);
  check(counts.length >= 3, "several notifications: " + counts.length);
  check(counts[counts.length - 1] === final, "last notification is the final count");
  for (let i = 1; i < counts.length; i++) {
    check(counts[i] > counts[i - 1], "on change: counts rise " + counts.slice(0, 10));
  }
  seen.notifications = counts.length;
  seen.final_count = final;
  await client.disconnect();
  console.log(JSON.stringify(seen));
}

main().catch((e) => {
  console.error("FAILED: " + (e && e.stack ? e.stack : e));
  process.exit(1);
});
