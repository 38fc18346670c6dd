// The link in sight: the round trip on the page's own state stream, the age of the newest state, whether the
// page's sockets are reconnecting, and the robot's dead-man per streamed point; one verdict: ok, degraded or lost.
// It only observes: the E-STOP (estop.js) is sent the same three ways whatever this says.
import {$, el, setClass, setText} from "./dom.js";
import {stickStream} from "./estop.js";
import {STALE_MS as LOST_MS, pollRoundTripMs, readState, telemetryMode, telemetryWs} from "./state.js";

export const PING_PERIOD_MS = 500;  // two pings a second on the state stream: a verdict within ~2 s, ~40 bytes each
export const RTT_DEGRADED_MS = 150;  // a let-go stick's zero then takes 75+ ms one way: the 0.25 s bound slips
export const PING_LOST_MS = 1000;  // a ping unanswered this long counts as lost (TCP has retransmitted it 2-3 times)
export const WINDOW = 10;  // the pings the verdict looks back on (5 s): one loss keeps the link degraded that long
export const STALE_MS = 500;  // the newest state older than this is stale: asked at 25 Hz, a dozen in a row missed
// (LOST_MS, state.js's 1 s: no state that long and the page says "connection lost")

const pings = [];  // the last WINDOW pings: round trip [ms], or null for a lost one
const pending = new Map();  // ping value (the page's clock when sent [ms]) -> sent
let boundWs = null;
let lastStateAt = null;  // the page's clock when the newest state (a new tick) came [ms]
let lastTick = null;
let deadman = {};  // point -> "streaming" | "ramping" | "stopped" (the operation layer's status)

function onPong(m) {
  if (typeof m.data !== "string" || !m.data.startsWith('{"pong"')) return;  // (a state: not parsed twice)
  let sent;
  try { sent = JSON.parse(m.data).pong; } catch (e) { return; }
  if (!pending.delete(sent)) return;  // answered after it was counted lost
  record(performance.now() - sent);
}
function record(rtt) {
  pings.push(rtt);
  if (pings.length > WINDOW) pings.shift();
}

// the round trip as the page lives it: the link and both ends' event loops (a page busy laying itself out counts)
function ping() {
  const now = performance.now();
  for (const sent of pending.keys()) if (now - sent > PING_LOST_MS) { pending.delete(sent); record(null); }
  const ws = telemetryWs;
  if (ws !== boundWs) {  // a new socket: the old one's pings are no one's
    pending.clear();
    if (ws) ws.addEventListener("message", onPong);
    boundWs = ws;
  }
  if (ws && ws.readyState === WebSocket.OPEN) {
    const value = Math.round(now * 1000) / 1000;
    pending.set(value, true);
    ws.send(JSON.stringify({ping: value}));
  } else if (telemetryMode === "polling" && pollRoundTripMs !== null) {
    record(pollRoundTripMs);  // no stream offered: the state polls' own timing
  }
}

function median(xs) {
  const s = [...xs].sort((a, b) => a - b);
  return s.length ? s[Math.floor(s.length / 2)] : null;
}

// the verdict and why: {verdict: "ok" | "degraded" | "lost", why: [short reasons], rtt, lost, age}
export function assess(now = performance.now()) {
  const answered = pings.filter((r) => r !== null);
  const lost = pings.length - answered.length;
  const rtt = median(answered);
  const age = lastStateAt === null ? null : now - lastStateAt;
  const reconnecting = telemetryMode !== "polling" && !(telemetryWs && telemetryWs.readyState === WebSocket.OPEN);
  const why = [];
  if (reconnecting) why.push("state stream reconnecting");
  if (!stickStream.ws) why.push("stick stream reconnecting");
  if (age === null || age > LOST_MS) {
    why.unshift(age === null ? "no state yet" : `no state for ${(age / 1000).toFixed(1)} s`);
    return {verdict: "lost", why, rtt, lost, age};
  }
  if (rtt === null) why.push("round trip not measured yet");
  else if (rtt > RTT_DEGRADED_MS) why.push(`round trip ${rtt.toFixed(0)} ms > ${RTT_DEGRADED_MS}`);
  if (lost) why.push(`${lost} of ${pings.length} pings lost`);
  if (age > STALE_MS) why.push(`state ${(age / 1000).toFixed(1)} s old`);
  return {verdict: why.length ? "degraded" : "ok", why, rtt, lost, age};
}

function deadmanText() {
  const live = Object.entries(deadman).filter(([, st]) => st !== "stopped").map(([p, st]) => `${p} ${st}`);
  return live.length ? live.join(", ") : "stopped";
}

let nodes = null;
function show() {
  const root = $("linkind");
  if (!root) return;
  const a = assess();
  if (!nodes) {
    nodes = {verdict: el("b", {id: "link-verdict"}), why: el("span", {id: "link-why"}),
             more: el("span", {id: "link-more"})};
    root.replaceChildren(nodes.verdict, nodes.why, nodes.more);
  }
  root.dataset.verdict = a.verdict;
  setText(nodes.verdict, `link ${a.verdict.toUpperCase()}`);
  setClass(nodes.verdict, `link-${a.verdict}`);
  setText(nodes.why, a.why.length ? ` (${a.why.join("; ")})` : "");
  const rtt = a.rtt === null ? "-" : `${a.rtt.toFixed(0)} ms`;
  const age = a.age === null ? "-" : `${(a.age / 1000).toFixed(1)} s`;
  setText(nodes.more, ` · round trip ${rtt} · state ${age} old · dead-man: ${deadmanText()}`);
  const title = `ok: round trip <= ${RTT_DEGRADED_MS} ms (median of the last ${WINDOW} pings), none unanswered ` +
    `within ${PING_LOST_MS} ms, state <= ${STALE_MS} ms old; lost: no state for ${LOST_MS} ms`;
  if (root.title !== title) root.title = title;
  window.hrp2Link = a;  // (the browser tests read it)
}

function onState(s) {
  if (s.tick !== lastTick) { lastTick = s.tick; lastStateAt = performance.now(); }
  const pts = (s.operation && s.operation.points) || {};
  deadman = {};
  for (const [p, st] of Object.entries(pts)) deadman[p] = st.deadman || "stopped";
}

export function watchLink() {
  readState(onState);
  setInterval(ping, PING_PERIOD_MS);
  setInterval(show, 250);  // (text written only when it changed: dom.js)
}
