// The live view's technology panel in a real headless browser (Debian's chromium driven by
// playwright-core from tests/node/node_modules, through tests/node/common.js): run by tests/web/techno.rs.
//
//   node tests/web/techno_view_test.js URL
//
// Opens the page, prints READY once the channel is shown live (the test then starts
// techno.nc), waits for M25 to appear among the units waiting for the PLC with its
// synchronisation type and unit, then for it to disappear once the channel acknowledged it
// after its process time (no PLC). Prints one JSON line (what it saw); exits non-zero on a
// failed check.
"use strict";
const path = require("path");
const { withChromium } = require(path.join(__dirname, "../node/common"));

async function main(url) {
  const seen = {};
  await withChromium({ viewport: { width: 1400, height: 900 } }, async (context) => {
    const page = await context.newPage();
    await page.goto(url);
    await page.locator("#ch1 .state").filter({ hasText: "READY" }).waitFor();
    await page.locator("#ch1 .techno-none").waitFor();
    console.log("READY");
    const row = page.locator('#ch1 .techno tbody tr[data-function="M25"]');
    await row.waitFor();
    const appeared = Date.now();
    seen.function = await row.locator(".function").textContent();
    seen.sync = await row.locator(".sync").textContent();
    seen.unit = await row.locator(".unit").textContent();
    seen.waited = await row.locator(".waited").textContent();
    seen.plc = await page.textContent("#ch1 .techno-plc");
    await row.waitFor({ state: "detached" });
    seen.shown_ms = Date.now() - appeared;
    seen.none_shown_after = await page.locator("#ch1 .techno-none").isVisible();
    seen.counts_after = await page.textContent("#ch1 .techno-counts");
    await page.close();
  });
  console.log(JSON.stringify(seen));
}

main(process.argv[2]).catch((e) => {
  console.error(e);
  process.exit(1);
});
