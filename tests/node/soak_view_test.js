// `serve --soak --http` in Debian's headless chromium (playwright-core): run by
// tests/web/browser.rs while an `ncchannel stream` client feeds the soaked channel.
//
//   node tests/node/soak_view_test.js URL
//
// Waits until the page's soak panel shows channel 1's checked blocks and accepted lines
// growing and the invariants listed. Prints one JSON line (what it saw).
"use strict";
const { check, withChromium } = require("./common");

async function main() {
  const url = process.argv[2];
  const seen = {};
  await withChromium({ viewport: { width: 1280, height: 800 } }, async (context) => {
    const page = await context.newPage();
    await page.goto(url);
    await page.locator("#soak").waitFor();
    await page.waitForFunction(() => {
      const td = document.querySelector("#soak tr[data-channel='1'] td.blocks");
      return td && Number(td.textContent) > 100;
    });
    const row = "#soak tr[data-channel='1'] td.";
    for (const k of ["blocks", "lines", "rejected", "resets", "program"]) {
      seen[k] = await page.textContent(row + k);
    }
    seen.invariants = await page.locator("#soak .invariants li").allTextContents();
    check(seen.invariants.length > 0, "invariants listed");
    seen.title = await page.textContent("#soak h2");
    await page.close();
  });
  console.log(JSON.stringify(seen));
}

main().catch((e) => {
  console.error("FAILED: " + (e && e.stack ? e.stack : e));
  process.exit(1);
});
