// The live view of a streamed program and of four channels in Debian's headless chromium
// at 1280×800 (playwright-core): run by tests/web/browser.rs.
//
//   node tests/node/live_view_stream_test.js URL
//
// The page is opened after channel 1's stream has run for a while and channel 4 has failed.
// It checks: the overview strip shows channel 4's ERROR with program and line above the fold;
// the streamed lines appear with the executing one highlighted; the backplot holds the path
// since the program started, its rapid dashed; spindle, tool, G codes and times are shown;
// the controls are disabled (read-only view). Prints one JSON line (what it saw); exits
// non-zero on a failed check.
"use strict";
const { check, withChromium } = require("./common");

async function main() {
  const url = process.argv[2];
  const seen = {};
  await withChromium({ viewport: { width: 1280, height: 800 } }, async (context) => {
    const page = await context.newPage();
    await page.goto(url);
    // Channel 4's error, at the top, above the fold.
    const ov4 = page.locator("#ov4.error");
    await ov4.waitFor();
    seen.ov4 = await ov4.textContent();
    const box = await ov4.boundingBox();
    seen.ov4_bottom = box.y + box.height;
    check(seen.ov4_bottom <= 800, "channel 4's overview above the fold: " + seen.ov4_bottom);
    seen.ch4_link = await ov4.getAttribute("href");
    // The mode and state badges read as two words.
    seen.badges = (await page.textContent("#ch1 h2")).replace(/\s+/g, " ").trim();
    // The streamed lines, the executing one highlighted.
    const current = page.locator("#ch1 .listing li.current");
    await current.waitFor();
    seen.current = await current.textContent();
    seen.done_lines = await page.locator("#ch1 .listing li.done").count();
    seen.lines = await page.locator("#ch1 .listing li").count();
    // The path since the program started: its rapid (dashed) and its cuts, though the page
    // connected after them.
    await page.waitForFunction(() => {
      const c = document.querySelector("#ch1 .plot");
      return Number(c.dataset.rapidSegments) > 0 && Number(c.dataset.cutSegments) > 1;
    });
    const plot = page.locator("#ch1 .plot");
    seen.rapid_segments = Number(await plot.getAttribute("data-rapid-segments"));
    seen.cut_segments = Number(await plot.getAttribute("data-cut-segments"));
    seen.path_bounds = (await plot.getAttribute("data-bounds")).split(",").map(Number);
    // Spindle, tool, G codes, times, the executing block's feed, the refused writes.
    await page.locator("#ch1 .spindle").filter({ hasText: "M03" }).waitFor();
    await page.locator("#ch1 .elapsed").filter({ hasText: /^\d+:\d\d$/ }).waitFor();
    await page.locator("#ch1 .feed").filter({ hasText: "F300" }).waitFor();
    for (const k of ["spindle", "tool", "gcodes", "work-offset", "elapsed", "feed", "block", "refused"]) {
      seen[k] = await page.textContent("#ch1 ." + k);
    }
    seen.start_disabled = await page.locator("#ch1 button[data-action=start]").isDisabled();
    // NCCHANNEL_SCREENSHOT=FILE.png keeps a picture of the page (the README's four channels).
    if (process.env.NCCHANNEL_SCREENSHOT) await page.screenshot({ path: process.env.NCCHANNEL_SCREENSHOT });
    await page.close();
  });
  console.log(JSON.stringify(seen));
}

main().catch((e) => {
  console.error("FAILED: " + (e && e.stack ? e.stack : e));
  process.exit(1);
});
