// What the Node test scripts share: a failed check ends the script with a message, a sleep, and
// the stream interface's packets (whole lines, CR LF, at most 992 bytes: ISG FCT-C19 Data
// streaming, the largest write of the program stream input).
"use strict";

function check(cond, what) {
  if (!cond) {
    console.error("FAILED: " + what);
    process.exit(1);
  }
}

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

function packets(lines) {
  const out = [];
  let packet = "";
  for (const line of lines) {
    const raw = line + "\r\n";
    if (packet.length + raw.length > 992) {
      out.push(packet);
      packet = "";
    }
    packet += raw;
  }
  out.push(packet);
  return out;
}

// An ads-client of the server at NCCHANNEL_ADS_ADDR (host:port), on the PLC port 851 by
// default, with the fixed local NetId and port the test server routes; `extra` overrides or
// adds any setting (`rawClient`, `targetAdsPort`, `timeoutDelay`).
function serverClient(localAdsPort, extra) {
  const { Client } = require("ads-client");
  const [host, port] = process.env.NCCHANNEL_ADS_ADDR.split(":");
  return new Client({
    targetAmsNetId: "127.0.0.1.1.1",
    targetAdsPort: 851,
    routerAddress: host,
    routerTcpPort: Number(port),
    localAmsNetId: "10.1.2.3.1.1",
    localAdsPort,
    autoReconnect: false,
    hideConsoleWarnings: true,
    ...extra,
  });
}

// How long a browser step (a wait, a click) may take before the check fails, ms.
const BROWSER_TIMEOUT_MS = 30000;

// Runs `body(context)` in Debian's headless chromium (NCCHANNEL_CHROMIUM, else
// /usr/bin/chromium) with a fresh profile, the given viewport (chromium's default when none)
// and any further command-line `args`; closes the browser and removes the profile whatever
// `body` does, and gives back what it returned.
async function withChromium({ viewport, args = [] }, body) {
  const fs = require("fs");
  const os = require("os");
  const path = require("path");
  const { chromium } = require("playwright-core");
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), "ncchannel-chromium-"));
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: process.env.NCCHANNEL_CHROMIUM || "/usr/bin/chromium",
    headless: true,
    viewport,
    args: [
      "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
      "--disable-background-networking", "--disable-component-update", "--disable-sync",
      ...args,
    ],
  });
  context.setDefaultTimeout(BROWSER_TIMEOUT_MS);
  try {
    return await body(context);
  } finally {
    await context.close();
    fs.rmSync(profile, { recursive: true, force: true });
  }
}

module.exports = { check, sleep, packets, serverClient, withChromium, BROWSER_TIMEOUT_MS };
