// The web view's guards in a real headless browser (Debian's chromium driven by
// playwright-core): run by tests/web/browser.rs.
//
//   node tests/node/guarded_view_test.js rebind PORT
//     a page served from a rebinding name (rebind.test mapped to 127.0.0.1 by chromium's
//     --host-resolver-rules) tries to start a program; prints what it got.
//   node tests/node/guarded_view_test.js full URL
//     opens the page while every page slot is taken; once it says it is retrying it prints
//     RETRYING, then waits until it is live. Prints one JSON line (what it saw).
"use strict";
const fs = require("fs");
const os = require("os");
const path = require("path");
const { chromium } = require("playwright-core");

const TIMEOUT_MS = 30000;

async function main() {
  const [mode, arg] = process.argv.slice(2);
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), "ncchannel-chromium-"));
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: process.env.NCCHANNEL_CHROMIUM || "/usr/bin/chromium",
    headless: true,
    args: [
      "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
      "--disable-background-networking", "--disable-component-update", "--disable-sync",
      "--host-resolver-rules=MAP rebind.test 127.0.0.1",
    ],
  });
  context.setDefaultTimeout(TIMEOUT_MS);
  const page = await context.newPage();
  let seen;
  if (mode === "rebind") {
    const url = "http://rebind.test:" + arg + "/";
    const resp = await page.goto(url);
    const start = await page.evaluate(async () => {
      const r = await fetch("/control/1/start", {
        method: "POST", headers: { "X-Ncchannel-Control": "1" }, body: "square.nc",
      });
      return { status: r.status, text: await r.text() };
    });
    seen = { page_status: resp.status(), start_status: start.status, start_text: start.text };
  } else {
    await page.goto(arg);
    const link = page.locator("#link");
    await page.waitForFunction(() => document.getElementById("link").textContent.includes("retrying"));
    const refused = await link.textContent();
    console.log("RETRYING");
    await page.waitForFunction(() => document.getElementById("link").textContent === "live");
    seen = { refused, retries: Number(await link.getAttribute("data-retries")), last: await link.textContent() };
  }
  await context.close();
  fs.rmSync(profile, { recursive: true, force: true });
  console.log(JSON.stringify(seen));
}

main().catch((e) => { console.error(e); process.exit(1); });
