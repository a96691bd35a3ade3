// Stream-interface throughput seen by the unmodified Node ads-client 2.x (rawClient mode): one
// sequential client streams 17-byte parameter lines (`N12345 P1=12345`, as
// `ncchannel bench --load ads-stream`) into channel 1 of a running `ncchannel serve`, packets
// of 58 lines (986 bytes), a write answered 0x708 (buffer full) sent again at once, for
// SECONDS after a 0.5 s warm-up. Prints one JSON line: bytes/s and the share of the
// interface's 4094 bytes per 1 ms cycle.
//
//   npm ci --prefix tests/node
//   NODE_PATH=tests/node/node_modules NCCHANNEL_ADS_ADDR=127.0.0.1:48898 \
//     node benches/clients/stream_rate.js [SECONDS]
"use strict";
const { Client } = require("ads-client");

const [host, port] = (process.env.NCCHANNEL_ADS_ADDR || "127.0.0.1:48898").split(":");
const GROUP = 0x20101;
const BUSY = 0x708;
const NOMINAL = 4094 / 0.001; // bytes/s: one full stream buffer per 1 ms cycle
const LINES_PER_PACKET = Math.floor(992 / 17);

function packet(k) {
  let s = "";
  for (let i = 0; i < LINES_PER_PACKET; i++) {
    const n = 10000 + ((k + i) % 90000);
    s += `N${n} P1=${n}\r\n`;
  }
  return Buffer.from(s, "latin1");
}

function int32(v) {
  const b = Buffer.alloc(4);
  b.writeInt32LE(v, 0);
  return b;
}

async function main() {
  const seconds = Number(process.argv[2] || 5);
  const client = new Client({
    targetAmsNetId: process.env.NCCHANNEL_ADS_NETID || "127.0.0.2.1.1",
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
  // A write answered busy (0x708: buffer full, or the cycle did not answer in time) is sent
  // again; anything else fails the run.
  const write = async (offset, data) => {
    for (;;) {
      try {
        return await client.writeRaw(GROUP, offset, data);
      } catch (e) {
        if ((e.adsError && e.adsError.errorCode) !== BUSY) throw e;
      }
    }
  };
  // A reset first: an earlier run may have left the streaming program running.
  await write(0x13c, int32(1));
  await write(0x104, int32(2));
  await write(0x108, Buffer.from("streaming.nc\0", "latin1"));
  await write(0x105, int32(4));
  const start = process.hrtime.bigint();
  const secs = () => Number(process.hrtime.bigint() - start) / 1e9;
  let t0 = null;
  let sent = 0;
  let busy = 0;
  for (let k = 0; ; k += LINES_PER_PACKET) {
    const p = packet(k);
    for (;;) {
      try {
        await client.writeRaw(GROUP, 0x90, p);
        break;
      } catch (e) {
        if ((e.adsError && e.adsError.errorCode) !== BUSY) throw e;
        if (t0 !== null) busy++;
      }
    }
    const now = secs();
    if (t0 === null) {
      if (now >= 0.5) t0 = now;
      continue;
    }
    sent += p.length;
    if (now - t0 >= seconds) break;
  }
  const elapsed = secs() - t0;
  await client.disconnect();
  const rate = sent / elapsed;
  console.log(JSON.stringify({
    client: "ads-client " + require("ads-client/package.json").version,
    bytes: sent,
    seconds: Number(elapsed.toFixed(3)),
    bytes_per_s: Math.round(rate),
    percent_of_4094_per_ms: Number(((100 * rate) / NOMINAL).toFixed(1)),
    busy,
  }));
}

main().catch((e) => {
  console.error(e);
  process.exit(1);
});
