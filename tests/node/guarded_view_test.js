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
const { withChromium } = require("./common");

async function main() {
  const [mode, arg] = process.argv.slice(2);
  const args = ["--host-resolver-rules=MAP rebind.test 127.0.0.1"];
  const seen = await withChromium({ args }, async (context) => {
    const page = await context.newPage();
    if (mode === "rebind") {
      const url = "http://rebind.test:" + arg + "/";
      const resp = await page.goto(url);
      const start = await page.evaluate(async () => {
        const r = await fetch("/control/1/start", {
          method: "POST", headers: { "X-Ncchannel-Control": "1" }, body: "square.nc",
        });
        return { status: r.status, text: await r.text() };
      });
      return { page_status: resp.status(), start_status: start.status, start_text: start.text };
    }
    await page.goto(arg);
    const link = page.locator("#link");
    await page.waitForFunction(() => document.getElementById("link").textContent.includes("retrying"));
    const refused = await link.textContent();
    console.log("RETRYING");
    await page.waitForFunction(() => document.getElementById("link").textContent === "live");
    return { refused, retries: Number(await link.getAttribute("data-retries")), last: await link.textContent() };
  });
  console.log(JSON.stringify(seen));
}

main().catch((e) => { console.error(e); process.exit(1); });
