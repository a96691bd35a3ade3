// ncchannel live view: reads the server's event stream (/events) and draws each channel's
// DRO, state, listing, stream fill, errors, the technology units waiting for the PLC, cycle
// statistics and backplot; sends the operator
// controls to /control/<channel>/<action>. Hand-written, no libraries.
"use strict";

const MAX_PLOT_POINTS = 100000; // per channel; beyond this every other point is dropped
const MAX_ERRORS_SHOWN = 32;
const channels = new Map(); // channel number -> view state
let updateTimes = [];

const $ = (root, sel) => root.querySelector(sel);
const fmt = (v, digits) => (v === null || v === undefined ? "–" : Number(v).toFixed(digits));

function channelView(ch) {
  let v = channels.get(ch);
  if (v) return v;
  const node = document.getElementById("channel-template").content.firstElementChild.cloneNode(true);
  node.id = "ch" + ch;
  $(node, ".ch-no").textContent = ch;
  document.getElementById("channels").appendChild(node);
  v = { ch, node, rows: new Map(), points: [], line: null, errors: new Set(), drawPending: false };
  wireControls(v);
  $(node, ".view").addEventListener("change", () => schedulePlot(v));
  $(node, ".clear").addEventListener("click", () => { v.points = []; schedulePlot(v); });
  channels.set(ch, v);
  return v;
}

// ---- the event stream ----

// A refused stream (503: every page slot taken) closes the EventSource for good; the page
// then retries itself, waiting 1 s, 2 s, 4 s … up to 30 s, and says so.
let retryDelayS = 1;

function connect() {
  const es = new EventSource("/events");
  const link = document.getElementById("link");
  es.onopen = () => { retryDelayS = 1; link.textContent = "live"; link.className = "link up"; };
  es.onerror = () => {
    link.className = "link down";
    if (es.readyState !== EventSource.CLOSED) { link.textContent = "reconnecting…"; return; }
    es.close();
    const wait = retryDelayS;
    retryDelayS = Math.min(retryDelayS * 2, 30);
    link.textContent = "refused (all page slots taken?) — retrying in " + wait + " s";
    link.dataset.retries = String(Number(link.dataset.retries || 0) + 1);
    setTimeout(connect, wait * 1000);
  };
  es.addEventListener("status", (e) => onStatus(JSON.parse(e.data)));
  es.addEventListener("listing", (e) => onListing(JSON.parse(e.data)));
  es.addEventListener("nc-error", (e) => onError(JSON.parse(e.data)));
}

function onStatus(u) {
  const now = performance.now();
  updateTimes.push(now);
  while (updateTimes.length && updateTimes[0] < now - 2000) updateTimes.shift();
  const rate = updateTimes.length > 1 ? (updateTimes.length - 1) / ((now - updateTimes[0]) / 1000) : 0;
  const rateEl = document.getElementById("rate");
  rateEl.textContent = rate.toFixed(1) + " Hz";
  rateEl.dataset.hz = rate.toFixed(2);
  rateEl.dataset.seq = u.seq;
  if (u.cycle) showCycle(u.cycle);
  for (const c of u.channels) showChannel(channelView(c.ch), c);
}

function showCycle(c) {
  const box = document.getElementById("cycle");
  const digits = { period_us: 0, ticks: 0, overruns: 0 };
  for (const el of box.querySelectorAll("[data-k]")) {
    const k = el.dataset.k;
    el.textContent = k === "period_us" ? fmt(c[k], 0) + " µs" : fmt(c[k], k in digits ? 0 : 1);
  }
}

function showChannel(v, c) {
  const n = v.node;
  const mode = $(n, ".mode"), state = $(n, ".state");
  mode.textContent = c.mode;
  state.textContent = c.state;
  state.className = "badge state " + c.state.toLowerCase();
  showDro(v, c);
  $(n, ".dtg").textContent = fmt(c.distance_to_go_mm, 3);
  $(n, ".feed").textContent = fmt(c.feed_mm_per_min, 0);
  $(n, ".vel").textContent = fmt(c.velocity_mm_per_s * 60, 0);
  $(n, ".ovr").textContent = fmt(c.override_pct, 0);
  $(n, ".block").textContent = c.block_n !== null ? "N" + c.block_n + " (#" + c.block_counter + ")" : "#" + c.block_counter;
  $(n, ".blocks").textContent = c.blocks;
  const total = c.stream_used_bytes + c.stream_free_bytes;
  $(n, ".fill").value = total ? c.stream_used_bytes / total : 0;
  $(n, ".fill-text").textContent = c.stream_used_bytes + " / " + total + " bytes";
  $(n, ".message").textContent = c.message ? "MSG: " + c.message : "";
  $(n, ".errors-total").textContent = c.errors_total ? "(" + c.errors_total + " raised)" : "";
  if (c.last_error) onError(Object.assign({ ch: c.ch }, c.last_error));
  showLine(v, c);
  showTechno(v, c.techno);
  addPoint(v, c.axes);
}

// ---- technology units waiting for the PLC ----

function showTechno(v, t) {
  const n = v.node;
  const plc = $(n, ".techno-plc");
  plc.textContent = t.plc_present
    ? "· PLC present: waits for done_w"
    : "· no PLC: the channel acknowledges after the process time";
  plc.className = "techno-plc " + (t.plc_present ? "present" : "absent");
  $(n, ".techno-counts").textContent = "· output " + t.output + " / acknowledged " + t.acknowledged;
  const body = $(n, ".techno tbody");
  // Few rows (at most one per unit): rebuilt on every update.
  body.textContent = "";
  for (const w of t.waiting) {
    const row = document.createElement("tr");
    row.dataset.function = w.function;
    row.dataset.set = w.set;
    row.dataset.unit = w.unit;
    if (!t.plc_present && w.waited_s * 1e6 > w.process_time_us) row.className = "overdue";
    const cells = [
      ["function", w.function],
      ["sync", w.sync],
      ["unit", w.set + " " + w.unit],
      ["fetched", w.please ? "no" : "yes"],
      ["since", fmt(w.output_at_s, 3) + " s"],
      ["waited", fmt(w.waited_s, 1) + " s of " + fmt(w.process_time_us / 1e6, 1) + " s"],
      ["line", w.line],
    ];
    for (const [cls, text] of cells) {
      const td = document.createElement("td");
      td.className = cls;
      td.textContent = text;
      row.appendChild(td);
    }
    body.appendChild(row);
  }
  $(n, ".techno-none").hidden = t.waiting.length > 0;
}

function showDro(v, c) {
  const body = $(v.node, ".dro tbody");
  for (const a of c.axes) {
    let row = v.rows.get(a.axis);
    if (!row) {
      row = document.createElement("tr");
      row.dataset.axis = a.axis;
      row.innerHTML = '<th></th><td class="pcs"></td><td class="mcs"></td>';
      row.firstChild.textContent = a.axis;
      body.appendChild(row);
      v.rows.set(a.axis, row);
    }
    $(row, ".pcs").textContent = fmt(a.pcs_mm, 3);
    $(row, ".mcs").textContent = fmt(a.mcs_mm, 3);
  }
}

// ---- listing ----

function onListing(l) {
  const v = channelView(l.ch);
  $(v.node, ".program-name").textContent = l.program || "–";
  const ol = $(v.node, ".listing");
  ol.textContent = "";
  const frag = document.createDocumentFragment();
  for (const text of l.lines) {
    const li = document.createElement("li");
    li.textContent = text;
    frag.appendChild(li);
  }
  if (l.lines_left_out) {
    const li = document.createElement("li");
    li.className = "left-out";
    li.textContent = "… " + l.lines_left_out + " more lines";
    frag.appendChild(li);
  }
  if (!l.lines.length) {
    const li = document.createElement("li");
    li.className = "left-out";
    li.textContent = "(no text to list: the stream, or a program that has ended)";
    frag.appendChild(li);
  }
  ol.appendChild(frag);
  v.line = null;
}

function showLine(v, c) {
  if (c.line === v.line) return;
  const ol = $(v.node, ".listing");
  const old = ol.querySelector("li.current");
  if (old) old.classList.remove("current");
  v.line = c.line;
  if (c.line === null) return;
  const li = ol.children[c.line - 1];
  if (!li) return;
  li.classList.add("current");
  ol.scrollTop = li.offsetTop - ol.offsetTop - ol.clientHeight / 2;
}

// ---- errors ----

function onError(e) {
  const v = channelView(e.ch);
  if (v.errors.has(e.index)) return;
  v.errors.add(e.index);
  const ul = $(v.node, ".errors");
  const li = document.createElement("li");
  li.dataset.code = e.code;
  li.textContent = e.code + ": " + e.text;
  ul.insertBefore(li, ul.firstChild);
  while (ul.children.length > MAX_ERRORS_SHOWN) ul.removeChild(ul.lastChild);
}

// ---- controls ----

function wireControls(v) {
  const form = $(v.node, ".controls");
  const answer = $(form, ".control-answer");
  const send = async (action, body) => {
    try {
      const r = await fetch("/control/" + v.ch + "/" + action, {
        method: "POST",
        headers: { "X-Ncchannel-Control": "1", "Content-Type": "text/plain" },
        body,
      });
      const text = await r.text();
      answer.textContent = action + ": " + (r.ok ? text : r.status + " " + text);
      answer.className = "control-answer " + (r.ok ? "ok" : "refused");
    } catch (err) {
      answer.textContent = action + ": " + err;
      answer.className = "control-answer refused";
    }
  };
  for (const b of form.querySelectorAll("button[data-action]")) {
    b.addEventListener("click", () => {
      const a = b.dataset.action;
      send(a, a === "start" ? $(form, ".program").value : "");
    });
  }
  const range = $(form, ".override");
  range.addEventListener("input", () => { $(form, ".override-value").textContent = range.value; });
  range.addEventListener("change", () => send("override", range.value));
}

// ---- backplot (1:1: one scale for every axis) ----

function addPoint(v, axes) {
  const get = (name) => { const a = axes.find((x) => x.axis === name); return a ? a.pcs_mm : 0; };
  const p = [get("X"), get("Y"), get("Z")];
  const last = v.points[v.points.length - 1];
  if (last && last[0] === p[0] && last[1] === p[1] && last[2] === p[2]) return;
  v.points.push(p);
  if (v.points.length > MAX_PLOT_POINTS) v.points = v.points.filter((_, i) => i % 2 === 0);
  schedulePlot(v);
}

function project(view, p) {
  switch (view) {
    case "xz": return [p[0], p[2]];
    case "yz": return [p[1], p[2]];
    case "iso": { // isometric: X to the lower right, Y to the upper right, Z up
      const c = Math.cos(Math.PI / 6), s = Math.sin(Math.PI / 6);
      return [(p[0] + p[1]) * c, p[2] + (p[1] - p[0]) * s];
    }
    default: return [p[0], p[1]];
  }
}

function schedulePlot(v) {
  if (v.drawPending) return;
  v.drawPending = true;
  requestAnimationFrame(() => { v.drawPending = false; drawPlot(v); });
}

function niceStep(span) {
  const raw = span / 8, p = Math.pow(10, Math.floor(Math.log10(raw || 1)));
  return [1, 2, 5, 10].map((m) => m * p).find((s) => s >= raw) || p * 10;
}

function drawPlot(v) {
  const canvas = $(v.node, ".plot");
  const view = $(v.node, ".view").value;
  const g = canvas.getContext("2d");
  const w = canvas.width, h = canvas.height, margin = 24;
  g.clearRect(0, 0, w, h);
  const pts = v.points.map((p) => project(view, p));
  if (!pts.length) return;
  let [x0, y0, x1, y1] = [Infinity, Infinity, -Infinity, -Infinity];
  for (const [x, y] of pts) { x0 = Math.min(x0, x); x1 = Math.max(x1, x); y0 = Math.min(y0, y); y1 = Math.max(y1, y); }
  const span = Math.max(x1 - x0, y1 - y0, 1);
  // One scale for both directions (a circle stays round), at most one canvas per mm.
  const fit = (px, mm) => (mm > 1e-9 ? px / mm : Infinity);
  const scale = Math.min(fit(w - 2 * margin, x1 - x0), fit(h - 2 * margin, y1 - y0), w - 2 * margin);
  const cx = (x0 + x1) / 2, cy = (y0 + y1) / 2;
  const sx = (x) => w / 2 + (x - cx) * scale, sy = (y) => h / 2 - (y - cy) * scale;
  drawGrid(g, w, h, niceStep(span), sx, sy, scale, cx, cy);
  g.strokeStyle = "#2d7ff9";
  g.lineWidth = 1.5;
  g.beginPath();
  pts.forEach(([x, y], i) => (i ? g.lineTo(sx(x), sy(y)) : g.moveTo(sx(x), sy(y))));
  g.stroke();
  const [tx, ty] = pts[pts.length - 1];
  g.fillStyle = "#e8590c";
  g.beginPath();
  g.arc(sx(tx), sy(ty), 4, 0, 2 * Math.PI);
  g.fill();
  const labels = { xy: "X → / Y ↑", xz: "X → / Z ↑", yz: "Y → / Z ↑", iso: "3-D isometric" };
  $(v.node, ".plot-scale").textContent = labels[view] + " · grid " + niceStep(span) + " mm · 1:1 · " + v.points.length + " points";
}

function drawGrid(g, w, h, step, sx, sy, scale, cx, cy) {
  g.strokeStyle = "#e3e7ee";
  g.lineWidth = 1;
  const left = cx - w / 2 / scale, right = cx + w / 2 / scale;
  const bottom = cy - h / 2 / scale, top = cy + h / 2 / scale;
  g.beginPath();
  for (let x = Math.ceil(left / step) * step; x <= right; x += step) { g.moveTo(sx(x), 0); g.lineTo(sx(x), h); }
  for (let y = Math.ceil(bottom / step) * step; y <= top; y += step) { g.moveTo(0, sy(y)); g.lineTo(w, sy(y)); }
  g.stroke();
}

async function showAccess() {
  const el = document.getElementById("access");
  try {
    const on = (await (await fetch("/controls")).text()) === "on";
    el.textContent = on ? "controls enabled" : "read-only (serve --http-controls enables the controls)";
    el.className = "access " + (on ? "on" : "off");
  } catch (err) {
    el.textContent = "";
  }
}

connect();
showAccess();
