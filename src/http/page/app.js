// ncchannel live view: reads the server's event stream (/events) and draws an overview of
// every channel, then each channel's DRO, state, spindle, tool, G codes, times, listing or
// streamed lines, stream fill, errors, the technology units waiting for the PLC, the cycle
// statistics (since the start and over the last seconds) and the backplot of the channel's
// path since its program started (rapids dashed); sends the operator controls to
// /control/<channel>/<action>. Hand-written, no libraries.
"use strict";

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
  v = { ch, node, rows: new Map(), path: [], tail: null, limits: [null, null, null], origin: [0, 0, 0],
    line: null, errors: new Set(), drawPending: false, streamListing: false, overview: null };
  wireControls(v);
  $(node, ".view").addEventListener("change", () => schedulePlot(v));
  $(node, ".show-limits").addEventListener("change", () => schedulePlot(v));
  channels.set(ch, v);
  setControlsEnabled(v);
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
  es.addEventListener("path", (e) => onPath(JSON.parse(e.data)));
  es.addEventListener("stream", (e) => onStream(JSON.parse(e.data)));
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
  if (u.window) showWindow(u.window);
  if (u.soak) showSoak(u.soak);
  for (const c of u.channels) showChannel(channelView(c.ch), c);
}

// ---- the overview strip: one link per channel ----

function showOverview(v, c) {
  if (!v.overview) {
    const a = document.createElement("a");
    a.href = "#ch" + c.ch;
    a.id = "ov" + c.ch;
    a.innerHTML = '<b></b> <span class="ov-mode"></span> <span class="ov-state"></span> <span class="ov-block"></span> <span class="ov-error"></span>';
    a.firstChild.textContent = "Ch " + c.ch;
    const nav = document.getElementById("overview");
    const after = [...nav.children].find((x) => Number(x.id.slice(2)) > c.ch);
    nav.insertBefore(a, after || null);
    v.overview = a;
  }
  const a = v.overview;
  a.className = "ov " + c.state.toLowerCase();
  $(a, ".ov-mode").textContent = c.mode;
  $(a, ".ov-state").textContent = c.state;
  $(a, ".ov-block").textContent = blockText(c);
  $(a, ".ov-error").textContent = c.state === "ERROR" && c.last_error ? errorText(c.last_error) : "";
}

function blockText(c) {
  const where = c.line !== null ? "line " + c.line : "";
  const n = c.block_n !== null ? "N" + c.block_n : "";
  return [n, where].filter(Boolean).join(" · ") || "–";
}

function errorText(e) {
  const at = e.program ? " (" + e.program + (e.line ? " line " + e.line : "") + ")" : "";
  return e.code + ": " + e.text + at;
}

// ---- serve --soak --http: the soak's counters and invariants ----

function showSoak(s) {
  const box = document.getElementById("soak");
  box.hidden = false;
  $(box, ".soak-time").textContent = "· " + duration(s.seconds) + " · " + s.blocks + " blocks checked";
  const body = $(box, ".soak-channels tbody");
  body.textContent = "";
  for (const c of s.channels) {
    const row = document.createElement("tr");
    row.dataset.channel = c.number;
    const errors = Object.entries(c.errors || {}).map(([k, n]) => k + "×" + n).join(" ") || "–";
    const cells = [c.number, c.program || "–", c.blocks, c.lines_accepted, c.writes_rejected, c.resets, c.lines_dropped, c.restarts, errors];
    const names = ["number", "program", "blocks", "lines", "rejected", "resets", "dropped", "restarts", "errors"];
    cells.forEach((text, i) => {
      const td = document.createElement("td");
      td.className = names[i];
      td.textContent = String(text);
      row.appendChild(td);
    });
    body.appendChild(row);
  }
  const ul = $(box, ".invariants");
  ul.textContent = "";
  for (const v of s.invariants) {
    const li = document.createElement("li");
    li.className = v.held ? "held" : "violated";
    li.dataset.name = v.name;
    li.textContent = (v.held ? "holds: " : "VIOLATED (" + v.violations + "): ") + v.name
      + (v.details && v.details.length ? " — " + v.details[0] : "");
    ul.appendChild(li);
  }
}

function showWindow(w) {
  const box = document.getElementById("window");
  box.hidden = false;
  for (const el of box.querySelectorAll("[data-w]")) {
    const k = el.dataset.w;
    el.textContent = k === "seconds" || k === "overruns" ? String(w[k]) : fmt(w[k], 1);
  }
  box.classList.toggle("overrun", w.overruns > 0);
  const t = document.getElementById("trend");
  const g = t.getContext("2d");
  g.clearRect(0, 0, t.width, t.height);
  const max = w.p99_trend_us.reduce((a, b) => Math.max(a, b), 1);
  const bw = t.width / 60;
  w.p99_trend_us.forEach((p, i) => {
    const h = (p / max) * (t.height - 2);
    g.fillStyle = "#5c7cfa";
    g.fillRect(i * bw, t.height - h, Math.max(bw - 1, 1), h);
  });
  t.dataset.seconds = w.p99_trend_us.length;
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
  showOverview(v, c);
  showDro(v, c);
  $(n, ".dtg").textContent = fmt(c.distance_to_go_mm, 3);
  $(n, ".feed").textContent = c.executing_rapid ? "rapid (G00)"
    : c.executing_feed_mm_per_min !== null ? "F" + fmt(c.executing_feed_mm_per_min, 0) + " mm/min" : "–";
  $(n, ".vel").textContent = fmt(c.velocity_mm_per_s * 60, 0);
  $(n, ".ovr").textContent = fmt(c.override_pct, 0);
  const sp = c.spindle;
  $(n, ".spindle").textContent = sp.direction === "off" ? "M05 stopped"
    : (sp.direction === "cw" ? "M03 clockwise" : "M04 counter-clockwise") + " · S" + fmt(sp.rpm, 0) + " rpm";
  $(n, ".tool").textContent = "T" + c.tool + " · D" + c.tool_offset;
  $(n, ".gcodes").textContent = c.g_codes.join(" ");
  const wo = c.work_offset_mm;
  $(n, ".work-offset").textContent = c.g_codes[c.g_codes.length - 1] + " · X" + fmt(wo[0], 3) + " Y" + fmt(wo[1], 3) + " Z" + fmt(wo[2], 3);
  v.origin = wo;
  $(n, ".block").textContent = blockText(c);
  $(n, ".blocks").textContent = c.blocks;
  $(n, ".elapsed").textContent = duration(c.elapsed_s);
  $(n, ".remaining").textContent = c.remaining_s === null ? "–" : "≈ " + duration(c.remaining_s);
  $(n, ".refused").textContent = c.stream_refused_full;
  $(n, ".stream-refused").classList.toggle("some", c.stream_refused_full > 0);
  const total = c.stream_used_bytes + c.stream_free_bytes;
  $(n, ".fill").value = total ? c.stream_used_bytes / total : 0;
  $(n, ".fill-text").textContent = c.stream_used_bytes + " / " + total + " bytes";
  $(n, ".message").textContent = c.message ? "MSG: " + c.message : "";
  $(n, ".errors-total").textContent = c.errors_total ? "(" + c.errors_total + " raised)" : "";
  if (c.last_error) onError(Object.assign({ ch: c.ch }, c.last_error));
  showLine(v, c);
  showTechno(v, c.techno);
}

function duration(s) {
  if (s === null || s === undefined) return "–";
  const t = Math.round(s), h = Math.floor(t / 3600), m = Math.floor((t % 3600) / 60), sec = t % 60;
  const two = (x) => String(x).padStart(2, "0");
  return (h ? h + ":" + two(m) : String(m)) + ":" + two(sec);
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
  l.lines.forEach((text, i) => {
    const li = document.createElement("li");
    li.textContent = text;
    // A click picks the line to run from.
    li.addEventListener("click", () => { $(v.node, ".from-line").value = String(i + 1); });
    frag.appendChild(li);
  });
  if (l.lines_left_out) {
    const li = document.createElement("li");
    li.className = "left-out";
    li.textContent = "… " + l.lines_left_out + " more lines";
    frag.appendChild(li);
  }
  v.streamListing = !l.lines.length;
  if (!v.streamListing && l.program) askPreview(v, l.program);
  ol.classList.toggle("streamed", v.streamListing);
  if (v.streamListing) {
    const li = document.createElement("li");
    li.className = "left-out";
    li.textContent = "(the stream: its lines appear as they are written)";
    frag.appendChild(li);
  }
  ol.appendChild(frag);
  v.line = null;
}

// ---- streamed lines: executed, executing, decoded, still in the buffer ----

function onStream(s) {
  const v = channelView(s.ch);
  if (!v.streamListing) return;
  const ol = $(v.node, ".listing");
  ol.textContent = "";
  const frag = document.createDocumentFragment();
  let current = null;
  for (const l of s.lines) {
    const li = document.createElement("li");
    li.textContent = l.text;
    li.className = l.state === "executing" ? "current" : l.state;
    li.title = { done: "executed", executing: "executing", decoded: "decoded, waiting to execute", buffered: "in the stream buffer" }[l.state];
    li.dataset.offset = l.offset;
    if (l.state === "executing") current = li;
    frag.appendChild(li);
  }
  ol.appendChild(frag);
  if (current) ol.scrollTop = current.offsetTop - ol.offsetTop - ol.clientHeight / 3;
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
  li.textContent = errorText(e);
  ul.insertBefore(li, ul.firstChild);
  while (ul.children.length > MAX_ERRORS_SHOWN) ul.removeChild(ul.lastChild);
}

// ---- controls ----

let controlsOn = null; // unknown until /controls answers

// Read-only: every control is disabled (and looks it); the server refuses them anyway.
function setControlsEnabled(v) {
  const form = $(v.node, ".controls");
  for (const el of form.querySelectorAll("button, input, select")) el.disabled = controlsOn !== true;
  form.classList.toggle("disabled", controlsOn !== true);
  form.title = controlsOn === false ? "read-only: serve --http-controls enables the controls" : "";
}

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
      const program = $(form, ".program").value.trim();
      if (a === "mdi") {
        send(a, $(form, ".mdi").value.trim());
      } else if (a === "run-from-line") {
        // The program named in the field, else the one listed.
        const listed = $(v.node, ".program-name").textContent;
        send(a, (program || listed) + "\n" + $(form, ".from-line").value.trim());
      } else {
        send(a, a === "start" ? program : "");
      }
    });
  }
  // Jog: an incremental move by the chosen step, through the channel's stream (as MDI).
  for (const b of form.querySelectorAll("button[data-jog]")) {
    b.addEventListener("click", () => {
      const j = b.dataset.jog, step = $(form, ".jog-step").value;
      send("jog", j[0] + (j.endsWith("-") ? "-" : "") + step);
    });
  }
  $(form, ".program").addEventListener("change", () => askPreview(v, $(form, ".program").value.trim()));
  const range = $(form, ".override");
  range.addEventListener("input", () => { $(form, ".override-value").textContent = range.value; });
  range.addEventListener("change", () => send("override", range.value));
}

// ---- whole-program preview: the program run on a private copy of the channel ----

async function askPreview(v, program) {
  if (!program || v.previewOf === program) return;
  v.previewOf = program;
  try {
    const r = await fetch("/preview/" + v.ch + "/" + encodeURIComponent(program));
    if (!r.ok) { if (r.status === 503) v.previewOf = null; return; }
    const p = await r.json();
    if (v.previewOf !== program) return;
    v.preview = p;
    schedulePlot(v);
  } catch (err) {
    v.previewOf = null;
  }
}

// ---- backplot: the channel's path since its program started (1:1, rapids dashed) ----

function onPath(p) {
  const v = channelView(p.ch);
  if (p.reset) v.path = p.points; else for (const q of p.points) v.path.push(q);
  v.tail = p.tail;
  v.limits = p.soft_limits_mm;
  v.tolerance = p.tolerance_mm;
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

// The soft-limit box's corners (machine coordinates), when X Y Z all have limits.
function limitBox(v) {
  const [x, y, z] = v.limits || [];
  if (!x || !y) return null;
  const zz = z || [0, 0];
  const c = [];
  for (const a of [x[0], x[1]]) for (const b of [y[0], y[1]]) for (const d of [zz[0], zz[1]]) c.push([a, b, d]);
  return c;
}

function drawPlot(v) {
  const canvas = $(v.node, ".plot");
  const view = $(v.node, ".view").value;
  const g = canvas.getContext("2d");
  const w = canvas.width, h = canvas.height, margin = 28;
  g.clearRect(0, 0, w, h);
  const pts = v.path.map((p) => project(view, p));
  const tail = v.tail ? project(view, v.tail) : null;
  const origin = project(view, v.origin);
  const pre = v.preview ? v.preview.points.map((p) => project(view, p)) : [];
  const fitPts = pts.concat(tail ? [tail] : [], [origin], pre);
  let [x0, y0, x1, y1] = [Infinity, Infinity, -Infinity, -Infinity];
  for (const [x, y] of fitPts) { x0 = Math.min(x0, x); x1 = Math.max(x1, x); y0 = Math.min(y0, y); y1 = Math.max(y1, y); }
  const span = Math.max(x1 - x0, y1 - y0, 1);
  // One scale for both directions (a circle stays round), at most one canvas per mm.
  const fit = (px, mm) => (mm > 1e-9 ? px / mm : Infinity);
  const scale = Math.min(fit(w - 2 * margin, x1 - x0), fit(h - 2 * margin, y1 - y0), w - 2 * margin);
  const cx = (x0 + x1) / 2, cy = (y0 + y1) / 2;
  const sx = (x) => w / 2 + (x - cx) * scale, sy = (y) => h / 2 - (y - cy) * scale;
  const step = niceStep(span);
  drawGrid(g, w, h, step, sx, sy, scale, cx, cy);
  // The soft-limit box (dotted red) where it is in view.
  const box = $(v.node, ".show-limits").checked ? limitBox(v) : null;
  if (box) {
    const b = box.map((p) => project(view, p));
    const edges = [[0, 1], [2, 3], [4, 5], [6, 7], [0, 2], [1, 3], [4, 6], [5, 7], [0, 4], [1, 5], [2, 6], [3, 7]];
    g.strokeStyle = "#e03131"; g.lineWidth = 1; g.setLineDash([2, 3]);
    g.beginPath();
    for (const [i, j] of edges) { g.moveTo(sx(b[i][0]), sy(b[i][1])); g.lineTo(sx(b[j][0]), sy(b[j][1])); }
    g.stroke();
    g.setLineDash([]);
  }
  // The whole program's preview, light, beneath the path so far.
  if (pre.length > 1) {
    g.strokeStyle = "#c5d3e8"; g.lineWidth = 3; g.setLineDash([]);
    g.beginPath();
    pre.forEach(([x, y], k) => (k ? g.lineTo(sx(x), sy(y)) : g.moveTo(sx(x), sy(y))));
    g.stroke();
  }
  canvas.dataset.previewPoints = pre.length;
  // The work origin (the active zero offset) as a cross.
  g.strokeStyle = "#2b8a3e"; g.lineWidth = 1.5;
  g.beginPath();
  g.moveTo(sx(origin[0]) - 7, sy(origin[1])); g.lineTo(sx(origin[0]) + 7, sy(origin[1]));
  g.moveTo(sx(origin[0]), sy(origin[1]) - 7); g.lineTo(sx(origin[0]), sy(origin[1]) + 7);
  g.stroke();
  // Cuts solid, rapids dashed: each run of one kind in one stroke.
  let rapids = 0, cuts = 0;
  g.lineWidth = 1.5;
  let i = 1;
  while (i < pts.length) {
    const rapid = v.path[i][3] === 1;
    g.strokeStyle = rapid ? "#e8590c" : "#1f5fbf";
    g.setLineDash(rapid ? [6, 4] : []);
    g.beginPath();
    g.moveTo(sx(pts[i - 1][0]), sy(pts[i - 1][1]));
    while (i < pts.length && (v.path[i][3] === 1) === rapid) {
      g.lineTo(sx(pts[i][0]), sy(pts[i][1]));
      if (rapid) rapids++; else cuts++;
      i++;
    }
    g.stroke();
  }
  if (tail && pts.length) {
    g.strokeStyle = v.tail[3] === 1 ? "#e8590c" : "#1f5fbf";
    g.setLineDash(v.tail[3] === 1 ? [6, 4] : []);
    g.beginPath();
    g.moveTo(sx(pts[pts.length - 1][0]), sy(pts[pts.length - 1][1]));
    g.lineTo(sx(tail[0]), sy(tail[1]));
    g.stroke();
  }
  g.setLineDash([]);
  canvas.dataset.rapidSegments = rapids;
  canvas.dataset.cutSegments = cuts;
  canvas.dataset.points = v.path.length;
  if (v.path.length) {
    const b = [Infinity, Infinity, -Infinity, -Infinity];
    for (const p of v.path) { b[0] = Math.min(b[0], p[0]); b[1] = Math.min(b[1], p[1]); b[2] = Math.max(b[2], p[0]); b[3] = Math.max(b[3], p[1]); }
    canvas.dataset.bounds = b.map((x) => x.toFixed(3)).join(",");
  }
  const at = tail || pts[pts.length - 1];
  if (at) {
    g.fillStyle = "#e8590c";
    g.beginPath();
    g.arc(sx(at[0]), sy(at[1]), 4, 0, 2 * Math.PI);
    g.fill();
  }
  const labels = { xy: "X → / Y ↑", xz: "X → / Z ↑", yz: "Y → / Z ↑", iso: "3-D isometric" };
  $(v.node, ".plot-scale").textContent = labels[view] + " machine mm · grid " + step + " mm · 1:1 · "
    + v.path.length + " points within " + fmt(v.tolerance || 0, 3) + " mm · rapids dashed · + work origin"
    + (v.preview ? " · light: the whole of " + v.preview.program + " (" + duration(v.preview.seconds) + (v.preview.complete ? "" : ", cut") + ")" : "");
}

function drawGrid(g, w, h, step, sx, sy, scale, cx, cy) {
  g.strokeStyle = "#e3e7ee";
  g.lineWidth = 1;
  const left = cx - w / 2 / scale, right = cx + w / 2 / scale;
  const bottom = cy - h / 2 / scale, top = cy + h / 2 / scale;
  const digits = step < 1 ? Math.ceil(-Math.log10(step)) : 0;
  g.beginPath();
  for (let x = Math.ceil(left / step) * step; x <= right; x += step) { g.moveTo(sx(x), 0); g.lineTo(sx(x), h); }
  for (let y = Math.ceil(bottom / step) * step; y <= top; y += step) { g.moveTo(0, sy(y)); g.lineTo(w, sy(y)); }
  g.stroke();
  // Axis numbers along the bottom and the left edge.
  g.fillStyle = "#66707c";
  g.font = "10px system-ui, sans-serif";
  for (let x = Math.ceil(left / step) * step; x <= right; x += step) g.fillText(x.toFixed(digits), sx(x) + 2, h - 3);
  for (let y = Math.ceil(bottom / step) * step; y <= top; y += step) g.fillText(y.toFixed(digits), 2, sy(y) - 2);
}

async function showAccess() {
  const el = document.getElementById("access");
  try {
    const on = (await (await fetch("/controls")).text()) === "on";
    el.textContent = on ? "controls enabled" : "read-only (serve --http-controls enables the controls)";
    el.className = "access " + (on ? "on" : "off");
    controlsOn = on;
    for (const v of channels.values()) setControlsEnabled(v);
  } catch (err) {
    el.textContent = "";
  }
}

connect();
showAccess();
