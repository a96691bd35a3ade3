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

module.exports = { check, sleep, packets };
