// The robot's state on the page: the telemetry (WS /ws/telemetry, else polling), the staleness watch, the safety
// bar's stop rows with their releases, the banner and latched alerts, the readouts, and its events in the history.
import {headers, latest, log, postLogged, wsUrl} from "./api.js";
import {$, fmt, setClass, setText} from "./dom.js";

// ---- the other stops, each with its own release ---------------------------------------------------------------
$("release").addEventListener("click", () => postLogged("/api/estop/release"));
$("motion-stop").addEventListener("click", () => postLogged("/api/motion/stop"));
$("motion-release").addEventListener("click", () => postLogged("/api/motion/release"));
$("walk-estop").addEventListener("click", () => postLogged("/api/walk/emergency-stop"));
$("walk-release").addEventListener("click", () => postLogged("/api/walk/stop"));
$("st-stop").addEventListener("click", () => postLogged("/api/stabilizer/stop"));
$("st-start").addEventListener("click", () => postLogged("/api/stabilizer/start"));

// ---- telemetry: WS /ws/telemetry when the console has it, else GET /api/state at 25 Hz; staleness watch -------
const RATE_HZ = 25;  // asked of the telemetry: a little over the 20 Hz the plots must be updated at
export const STALE_MS = 1000;
let lastFreshAt = performance.now();
export let telemetryMode = "connecting";
export let pollRoundTripMs = null;  // the last state poll's round trip [ms] (the link indicator's, when polling)

export let telemetryWs = null;
export function startTelemetry() {
  let opened = false;
  let ws;
  try {
    ws = new WebSocket(wsUrl(`/ws/telemetry?rate_hz=${RATE_HZ}`));
  } catch (e) {
    pollState();
    return;
  }
  telemetryWs = ws;
  ws.onopen = () => { opened = true; telemetryMode = "telemetry"; };
  ws.onmessage = (m) => { try { onState(JSON.parse(m.data)); } catch (e) { /* a bad frame is skipped */ } };
  ws.onclose = () => {
    if (telemetryWs === ws) telemetryWs = null;
    if (!opened) { telemetryMode = "polling"; pollState(); return; }  // not offered: poll instead
    setTimeout(startTelemetry, ws.renewed ? 0 : 500);  // was offered: reconnect
  };
}

async function pollState() {
  const t0 = performance.now();
  try {
    const ctl = new AbortController();
    const timer = setTimeout(() => ctl.abort(), STALE_MS);
    const r = await fetch("/api/state", {headers: headers(false), signal: ctl.signal, cache: "no-store"});
    clearTimeout(timer);
    if (r.ok) { pollRoundTripMs = performance.now() - t0; onState(await r.json()); }
  } catch (e) { /* the staleness watch says so */ }
  setTimeout(pollState, Math.max(0, 1000 / RATE_HZ - (performance.now() - t0)));
}

function watchStaleness() {
  const age = performance.now() - lastFreshAt;
  const offline = age > STALE_MS;
  document.body.classList.toggle("offline", offline);
  $("offline").hidden = !offline;
  setClass($("conn"), offline ? "bad" : "");
  if (offline) {
    const why = latest.state === null ? "no state received yet." : `the last state is ${(age / 1000).toFixed(1)} s old.`;
    setText($("offline-why"), why);
    setText($("conn"), "connection lost");
  } else {
    setText($("conn"), `live (${telemetryMode})`);
  }
}
setInterval(watchStaleness, 100);

// ---- the state: safety bar, banner, latched alerts, readouts, events into the history ------------------------
let acknowledged = null;
// what else each state updates (the runs, the journal, the lock, the plots...), called in the order given
const readers = [];
export function readState(...fns) { readers.push(...fns); }

function setStop(row, on, text) {
  $(row).classList.toggle("on", on);
}

function onState(s) {
  if (!s || typeof s !== "object" || s.time === undefined) return;
  const prev = latest.state;
  if (!prev || s.tick !== prev.tick || s.time !== prev.time) lastFreshAt = performance.now();
  latest.state = s;
  const em = s.emergency || {};
  setText($("s-time"), `${fmt(s.time)} s (tick ${s.tick})`);

  setText($("s-hard"), em.hard_stop ? (em.hard_stop_stopping ? `ENGAGED (${em.hard_stop_stopping})` : "ENGAGED") : "off");
  setClass($("s-hard"), "st" + (em.hard_stop ? " alarm" : ""));
  setStop("stop-hard", !!em.hard_stop);
  setText($("s-motion"), em.motion_stop ? `STOPPED (${em.motion_stop_reason || "?"})` : "off");
  setStop("stop-motion", !!em.motion_stop);
  setText($("s-walkstop"), em.walking_stop ? "STOPPING in place" : (em.walk_cut ? `off (last walk cut: ${em.walk_cut})` : "off"));
  setStop("stop-walking", !!em.walking_stop);
  setText($("s-ststop"), em.stabilizer_stop ? "STOPPED" : "running");
  setStop("stop-stabilizer", !!em.stabilizer_stop);

  if ($("banner").hidden !== !em.hard_stop) $("banner").hidden = !em.hard_stop;
  setText($("banner-why"), em.hard_stop
    ? [em.hard_stop_reason && `reason: ${em.hard_stop_reason}`, em.fault && `fault: ${em.fault}`,
       "Release is the green control in the hard row."].filter(Boolean).join("; ") : "");

  // latched stops (not the operator's own): raised as an alert until acknowledged
  let latched = null;
  if (s.fallen) latched = {key: "fall", text: `the robot has fallen (${em.fall || "?"}); reset the simulation.`};
  else if (em.fault) latched = {key: `fault:${em.fault}`, text: `fault: ${em.fault} (the hard stop is engaged).`};
  else if (em.motion_stop && em.motion_stop_reason && em.motion_stop_reason !== "operator") {
    // the CP error that raised the flag, not the value now (it has fallen back by the time one reads it)
    const raisedBy = em.motion_stop_cp_error_m != null
      ? ` (CP error ${fmt(1000 * em.motion_stop_cp_error_m, 1)} mm when the flag rose)` : "";
    latched = {key: `motion:${em.motion_stop_time}`, text: `motion stop latched by ${em.motion_stop_reason} at ` +
      `${fmt(em.motion_stop_time, 3)} s${raisedBy}. Balance keeps working; release it in the motion row or the dialogue.`};
  }
  const showLatched = latched !== null && latched.key !== acknowledged;
  $("latched").hidden = !showLatched;
  if (showLatched) setText($("latched-text"), latched.text);
  $("latched").dataset.key = latched ? latched.key : "";

  setText($("s-fallen"), s.fallen ? "FALLEN" : "no");
  setClass($("s-fallen"), s.fallen ? "alarm" : "");
  setText($("s-fault"), em.fault || "none");
  setClass($("s-fault"), em.fault ? "alarm" : "");
  setText($("s-height"), s.base ? `${fmt(s.base.pos[2])} m` : "-");
  setText($("s-rpy-est"), s.estimate ? s.estimate.rpy_deg.map((v) => fmt(v, 1)).join(", ") + " deg" : "-");
  setText($("s-support"), `${s.walking ? "walking" : "standing"}, support ${s.support}`);
  const cp = s.capture_point || {};
  if (cp.error) {
    setText($("s-cp"), `${fmt(cp.error_norm * 1000, 1)} mm (x ${fmt(cp.error[0] * 1000, 1)}, ` +
      `y ${fmt(cp.error[1] * 1000, 1)}; threshold ${fmt(cp.cp_threshold_m * 1000, 1)} mm)`);
  }
  setText($("s-flag"), em.flag ? "RAISED" : "off");
  setClass($("s-flag"), em.flag ? "alarm" : "");
  setText($("s-chain"), s.chain || "-");

  if (prev) {
    const pe = prev.emergency || {};
    // (the stops and a fall are the dialogue's questions: js/dialogue.js)
    if (em.fault && em.fault !== pe.fault) log(`FAULT: ${em.fault}`, "bad");
    if (em.flag && !pe.flag) {
      const cp = em.flag_cp_error_m != null ? ` (CP error ${fmt(1000 * em.flag_cp_error_m, 1)} mm)` : "";
      log(`capture-point flag raised${cp} at ${fmt(em.flag_rose_at, 3)} s`, "bad");
    }
    if (s.scene !== prev.scene) log(`scene is now ${s.scene}`, "other");
  }
  for (const read of readers) read(s);
}
$("latched-ack").addEventListener("click", () => { acknowledged = $("latched").dataset.key; $("latched").hidden = true; });
