// ncchannel's live web view in a real headless browser (Debian's chromium driven by
// playwright-core): run by tests/web/browser.rs.
//
//   node tests/node/live_view_test.js READ_ONLY_URL CONTROLS_URL
//
// With the read-only view: the controls are refused with the server's message. With the
// controls view: Start runs square.nc, the DRO's positions change, the listing highlights the
// executing block, Hold holds; then it prints READY_FOR_ERROR and waits for the error the test
// raises on channel 2's stream to appear. Prints one JSON line (what it saw); exits non-zero on
// a failed check.
//
//   node tests/node/live_view_test.js --screenshot URL FILE.png SECONDS
//
// takes a picture of the page after SECONDS (the README's docs/live-view.png).
"use strict";
const { check, withChromium, BROWSER_TIMEOUT_MS } = require("./common");

// The browser every check of this script runs in (a large viewport: both pages' panels).
const VIEWPORT = { viewport: { width: 1400, height: 900 } };

// Every request the page makes must go to the view itself.
function watchRequests(page, origin, foreign) {
  page.on("request", (r) => {
    if (!r.url().startsWith(origin)) foreign.push(r.url());
  });
}

async function readOnly(context, url, seen) {
  const page = await context.newPage();
  watchRequests(page, new URL(url).origin, seen.foreign);
  await page.goto(url);
  await page.locator("#ch1 .state").filter({ hasText: "READY" }).waitFor();
  await page.locator("#access.off").waitFor();
  // The controls look disabled, and a start sent anyway is refused with the server's reason.
  check(await page.locator("#ch1 button[data-action=start]").isDisabled(), "start disabled");
  check(await page.locator("#ch1 button[data-action=mdi]").isDisabled(), "MDI disabled");
  check(await page.locator("#ch1 button[data-jog=X]").isDisabled(), "jog disabled");
  seen.refused = await page.evaluate(async () => {
    const r = await fetch("/control/1/start", {
      method: "POST",
      headers: { "X-Ncchannel-Control": "1" },
      body: "square.nc",
    });
    return r.status + " " + (await r.text());
  });
  check(seen.refused.includes("403") && seen.refused.includes("--http-controls"), "refusal shown: " + seen.refused);
  seen.state_after_refusal = await page.textContent("#ch1 .state");
  await page.close();
}

async function waitForChange(page, selector, before) {
  await page.waitForFunction(
    ([sel, old]) => document.querySelector(sel).textContent !== old,
    [selector, before],
    { timeout: BROWSER_TIMEOUT_MS },
  );
  return page.textContent(selector);
}

async function withControls(context, url, seen) {
  const page = await context.newPage();
  watchRequests(page, new URL(url).origin, seen.foreign);
  await page.goto(url);
  await page.locator("#access.on").waitFor();
  // MDI and jog move the axes (through the channel's stream), and the DRO shows it.
  await page.fill("#ch1 .mdi", "G01 X5 F3000");
  await page.click("#ch1 button[data-action=mdi]");
  await page.locator("#ch1 .dro tr[data-axis=X] .mcs").filter({ hasText: /^5\.000$/ }).waitFor();
  await page.locator("#ch1 .state").filter({ hasText: "READY" }).waitFor();
  await page.click("#ch1 button[data-jog=Y]");
  await page.locator("#ch1 .dro tr[data-axis=Y] .mcs").filter({ hasText: /^1\.000$/ }).waitFor();
  await page.locator("#ch1 .state").filter({ hasText: "READY" }).waitFor();
  seen.mdi_jog = await page.textContent("#ch1 .dro tbody");
  await page.fill("#ch1 .program", "square.nc");
  await page.click("#ch1 button[data-action=start]");
  await page.locator("#ch1 .control-answer.ok").waitFor();
  await page.locator("#ch1 .state").filter({ hasText: "ACTIVE" }).waitFor();
  // Positions that change while the program runs.
  const x = "#ch1 .dro tr[data-axis=X] .pcs";
  seen.x = [await page.textContent(x)];
  seen.x.push(await waitForChange(page, x, seen.x[0]));
  seen.x.push(await waitForChange(page, x, seen.x[1]));
  // The executing block highlighted in the listing: its N number is the DRO's block.
  await page.locator("#ch1 .listing li.current").waitFor();
  seen.current_line = await page.textContent("#ch1 .listing li.current");
  seen.block = await page.textContent("#ch1 .block");
  seen.listing_lines = await page.locator("#ch1 .listing li").count();
  // The whole program's preview under the path so far.
  await page.waitForFunction(() => Number(document.querySelector("#ch1 .plot").dataset.previewPoints) > 1);
  seen.preview_points = Number(await page.getAttribute("#ch1 .plot", "data-preview-points"));
  // The update rate the page measured, after it has had two seconds of updates.
  await page.waitForTimeout(2500);
  seen.update_hz = Number(await page.getAttribute("#rate", "data-hz"));
  // Override and hold through the controls.
  await page.locator("#ch1 .override").evaluate((el) => {
    el.value = "50";
    el.dispatchEvent(new Event("change"));
  });
  await page.locator("#ch1 .ovr").filter({ hasText: /^50$/ }).waitFor();
  await page.click("#ch1 button[data-action=hold]");
  await page.locator("#ch1 .state").filter({ hasText: "HOLD" }).waitFor();
  seen.held = true;
  // An error raised while the page watches.
  console.log("READY_FOR_ERROR");
  const error = page.locator("#ch2 .errors li").first();
  await error.waitFor();
  seen.error = await error.textContent();
  seen.ch2_state = await page.locator("#ch2 .state").filter({ hasText: "ERROR" }).textContent();
  await page.close();
}

async function screenshot(url, file, seconds) {
  await withChromium(VIEWPORT, async (context) => {
    const page = await context.newPage();
    await page.goto(url);
    await page.waitForTimeout(seconds * 1000);
    await page.screenshot({ path: file, fullPage: true });
  });
}

async function main() {
  if (process.argv[2] === "--screenshot") {
    await screenshot(process.argv[3], process.argv[4], Number(process.argv[5] || 5));
    return;
  }
  const [readOnlyUrl, controlsUrl] = process.argv.slice(2);
  const seen = { foreign: [] };
  await withChromium(VIEWPORT, async (context) => {
    await readOnly(context, readOnlyUrl, seen);
    await withControls(context, controlsUrl, seen);
  });
  console.log(JSON.stringify(seen));
}

main().catch((e) => {
  console.error("FAILED: " + (e && e.stack ? e.stack : e));
  process.exit(1);
});
