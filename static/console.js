// The operator console page: safety bar, telemetry, teleoperation (sticks, gamepad, keys), behaviours, command
// box, controller management. Everything it offers comes from the API's own documents (GET /api/behaviors, the
// OpenAPI schema of PUT /api/params, /api/config): nothing here is written per behaviour or per parameter.
"use strict";

const $ = (id) => document.getElementById(id);
const fmt = (v, d = 3) => (v === null || v === undefined || Number.isNaN(Number(v))) ? "-" : Number(v).toFixed(d);
const el = (tag, attrs = {}, ...children) => {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "class") e.className = v;
    else if (k === "text") e.textContent = v;
    else if (k.startsWith("on")) e.addEventListener(k.slice(2), v);
    else if (v !== undefined && v !== null && v !== false) e.setAttribute(k, v === true ? "" : v);
  }
  for (const c of children) e.append(c);
  return e;
};
// Writes only what changed. The browser lays the page out again after any write, an unchanged one too, and this
// page's thread does that work in the way of its input: the E-STOP's pointer-down waits behind it.
function setText(node, text) { if (node.textContent !== text) node.textContent = text; }
function setClass(node, cls) { if (node.className !== cls) node.className = cls; }

// ---- the token, the client id and the lock's lease (contract with the API): kept in memory only --------------
const TOKEN = new URLSearchParams(location.search).get("token");
if (TOKEN) history.replaceState(null, "", location.pathname);  // not left in the address bar
const CLIENT_ID = "page-" + Math.random().toString(36).slice(2, 10);  // a display name: it proves nothing
let lockToken = null;  // the operator lock's lease token while this page holds it: secret, never shown or logged

function headers(json = true) {
  const h = {"X-Client-Id": CLIENT_ID};
  if (json) h["Content-Type"] = "application/json";
  if (TOKEN) h["Authorization"] = `Bearer ${TOKEN}`;
  if (lockToken) h["X-Lock-Token"] = lockToken;
  return h;
}
function wsUrl(path) {
  const url = new URL(path, location.href);
  url.protocol = location.protocol === "https:" ? "wss:" : "ws:";
  if (TOKEN) url.searchParams.set("token", TOKEN);
  url.searchParams.set("client", CLIENT_ID);
  if (lockToken) url.searchParams.set("lock_token", lockToken);  // the holder's stream; an open one keeps the lock
  return url.href;
}

// ---- history: commands, results, faults, what other clients did ---------------------------------------------
function log(text, kind = "") {
  const h = $("history");
  const t = lastState ? `${fmt(lastState.time, 2)} s ` : "";
  h.append(el("li", {class: kind, text: t + text}));
  while (h.children.length > 300) h.firstChild.remove();
  h.scrollTop = h.scrollHeight;
}
function say(text, bad = false) {
  const m = $("message");
  m.textContent = text;
  m.className = bad ? "alarm" : "";
}

async function api(method, url, body) {
  try {
    const r = await fetch(url, {method, headers: headers(method !== "GET"),
                                body: body === undefined ? undefined : JSON.stringify(body)});
    const data = await r.json().catch(() => ({}));
    if (!r.ok) {
      const why = r.status === 423 ? `another operator holds control (${data.holder || data.detail || "?"})`
        : (data.detail || r.statusText);
      const text = `${method} ${url}: ${r.status} ${typeof why === "string" ? why : JSON.stringify(why)}`;
      say(text, true);
      log(text, "bad");
      return null;
    }
    if (data.message) say(data.message);
    return data;
  } catch (e) {
    say(`${method} ${url}: ${e}`, true);
    log(`${method} ${url}: ${e}`, "bad");
    return null;
  }
}
const post = (url, body) => api("POST", url, body);

// ---- E-STOP: pointer-down (not click: no waiting for the release), Space / Esc anywhere, gamepad B ----------
let lastEstopAt = -1e9;
const estopsOnWs = [];  // the e-stops sent on the stick stream, answered in order
// the e-stops this page sent: input event time (epoch [ms]) and the loop's reply (the e-stop benchmark reads it)
window.hrp2Estops = [];
let presses = 0;
function estop(source, eventTimeStamp) {
  lastEstopAt = performance.now();
  const now = performance.now();
  // one id for the press on all three ways: the first to arrive engages; a copy arriving after a quick release
  // is that press again, not a new one (it engages nothing)
  const press = `${CLIENT_ID}:${++presses}`;
  const message = JSON.stringify({estop: true, press});
  const record = {source, press, event_epoch_ms: performance.timeOrigin + (eventTimeStamp ?? now),
                  handled_epoch_ms: performance.timeOrigin + now, reply: null};
  window.hrp2Estops.push(record);
  if (window.hrp2Estops.length > 1000) window.hrp2Estops.shift();
  // three ways in, whichever answers first: the e-stop's own door into the robot process (it does not wait for
  // the console), the stick stream's open socket (no new request to set up) and a POST
  if (doorWs && doorWs.readyState === WebSocket.OPEN) {
    estopsOnDoor.push(record);
    doorWs.send(message);
  }
  if (opWs && opWs.readyState === WebSocket.OPEN) {
    estopsOnWs.push(record);
    opWs.send(message);
  }
  fetch("/api/estop", {method: "POST", headers: {...headers(false), "X-Estop-Press": press}, keepalive: true})
    .then((r) => r.json().then((d) => {
      if (record.reply === null) record.reply = d;
      if (!r.ok && !d.late_copy) log(`E-STOP (${source}): ${r.status} ${d.detail || d.message}`, "bad");
    }))
    .catch((e) => log(`E-STOP (${source}) not sent: ${e}`, "bad"));
  log(`E-STOP pressed (${source})`, "bad");
}
$("estop").addEventListener("pointerdown", (e) => { e.preventDefault(); estop("button", e.timeStamp); });

// The e-stop's own door (GET /api/config's estop_port): a socket to the robot process itself, served between its
// ticks; kept open, reopened when it closes. Without it (no port, or not reachable) the other two ways remain.
let doorWs = null;
let doorPort = null;
const estopsOnDoor = [];  // the e-stops sent on the door, answered in order
function connectDoor() {
  if (!doorPort) return;
  const host = location.hostname.includes(":") ? `[${location.hostname}]` : location.hostname;
  const url = new URL(`${location.protocol === "https:" ? "wss" : "ws"}://${host}:${doorPort}/`);
  if (TOKEN) url.searchParams.set("token", TOKEN);
  let ws;
  try { ws = new WebSocket(url.href); } catch (e) { setTimeout(connectDoor, 2000); return; }
  ws.onopen = () => { doorWs = ws; };
  ws.onmessage = (m) => {
    const rec = estopsOnDoor.shift();
    let d = {};
    try { d = JSON.parse(m.data); } catch (e) { return; }
    if (rec) rec.door_reply = d;
    if (rec && rec.reply === null) rec.reply = d;
    if (d.ok === false && !d.late_copy) log(`E-STOP door: ${d.detail || d.message}`, "bad");
  };
  ws.onclose = () => {
    if (doorWs === ws) doorWs = null;
    estopsOnDoor.length = 0;  // answered no more: the other ways answer them
    setTimeout(connectDoor, 2000);
  };
}
$("estop").addEventListener("click", () => { if (performance.now() - lastEstopAt > 500) estop("button"); });

function isTyping(target) {
  if (!target || !target.tagName) return false;
  const tag = target.tagName.toUpperCase();
  if (tag === "TEXTAREA" || target.isContentEditable) return true;
  if (tag !== "INPUT") return false;
  return !["button", "checkbox", "radio", "range", "submit", "reset", "file", "color"].includes(
    (target.type || "text").toLowerCase());
}

const KEY_AXES = {  // held keys -> (axis, sign); axes: L fwd, L left, L twist, R fwd, R left, R twist
  KeyW: [0, 1], KeyS: [0, -1], KeyA: [1, 1], KeyD: [1, -1], KeyQ: [2, 1], KeyE: [2, -1],
  ArrowUp: [3, 1], ArrowDown: [3, -1], ArrowLeft: [4, 1], ArrowRight: [4, -1], KeyZ: [5, 1], KeyC: [5, -1],
};
const KEY_DEFLECTION = 0.5;
const heldKeys = new Set();

function onKeyDown(e) {
  if (e.key === "Escape" || e.code === "Space" || e.key === " ") {
    if (isTyping(e.target)) return;
    e.preventDefault();
    e.stopPropagation();
    if (!e.repeat) estop(e.key === "Escape" ? "Esc" : "Space");
    return;
  }
  if (isTyping(e.target) || e.ctrlKey || e.metaKey || e.altKey) return;
  if (/^Digit[1-9]$/.test(e.code)) {
    const k = Number(e.code.slice(5)) - 1;
    if (k < POINTS.length) { selectPoint(POINTS[k]); e.preventDefault(); }
    return;
  }
  if (KEY_AXES[e.code]) { heldKeys.add(e.code); e.preventDefault(); }
}
function onKeyUp(e) {
  // a teleoperation key let go: the zero goes out at once, not at the next 50 Hz send (as a stick's)
  if (heldKeys.delete(e.code)) streamTick();
}
window.addEventListener("keydown", onKeyDown, true);
window.addEventListener("keyup", onKeyUp, true);
window.addEventListener("blur", () => heldKeys.clear());

// ---- the other stops, each with its own release ---------------------------------------------------------------
$("release").addEventListener("click", () => post("/api/estop/release").then((d) => d && log(d.message, "ok")));
$("motion-stop").addEventListener("click", () => post("/api/motion/stop").then((d) => d && log(d.message, "ok")));
$("motion-release").addEventListener("click", () => post("/api/motion/release").then((d) => d && log(d.message, "ok")));
$("walk-estop").addEventListener("click", () => post("/api/walk/emergency-stop").then((d) => d && log(d.message, "ok")));
$("walk-release").addEventListener("click", () => post("/api/walk/stop").then((d) => d && log(d.message, "ok")));
$("st-stop").addEventListener("click", () => post("/api/stabilizer/stop").then((d) => d && log(d.message, "ok")));
$("st-start").addEventListener("click", () => post("/api/stabilizer/start").then((d) => d && log(d.message, "ok")));

// ---- telemetry: WS /ws/telemetry when the console has it, else GET /api/state at 25 Hz; staleness watch -------
const RATE_HZ = 25;  // asked of the telemetry: a little over the 20 Hz the plots must be updated at
const STALE_MS = 1000;
let lastState = null;
let lastFreshAt = performance.now();
let telemetryMode = "connecting";

let telemetryWs = null;
function startTelemetry() {
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
    if (r.ok) onState(await r.json());
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
    const why = lastState === null ? "no state received yet." : `the last state is ${(age / 1000).toFixed(1)} s old.`;
    setText($("offline-why"), why);
    setText($("conn"), "connection lost");
  } else {
    setText($("conn"), `live (${telemetryMode})`);
  }
}
setInterval(watchStaleness, 100);

// ---- the state: safety bar, banner, latched alerts, readouts, events into the history ------------------------
let acknowledged = null;
const myRuns = new Set();
const knownRuns = new Map();  // id -> state

function setStop(row, on, text) {
  $(row).classList.toggle("on", on);
}

function onState(s) {
  if (!s || typeof s !== "object" || s.time === undefined) return;
  const prev = lastState;
  if (!prev || s.tick !== prev.tick || s.time !== prev.time) lastFreshAt = performance.now();
  lastState = s;
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
      `${fmt(em.motion_stop_time, 3)} s${raisedBy}. Balance keeps working; release it in the motion row.`};
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

  const op = s.operation && s.operation.points && s.operation.points[selected];
  const limited = op ? op.limited : null;
  setText($("limited"), limited || "no");
  setClass($("limited"), limited ? "alarm" : "");

  if (prev) {
    const pe = prev.emergency || {};
    if (em.hard_stop && !pe.hard_stop) log(`hard stop engaged${em.hard_stop_reason ? ` (${em.hard_stop_reason})` : ""}`, "bad");
    if (!em.hard_stop && pe.hard_stop) log("hard stop released", "ok");
    if (em.motion_stop && !pe.motion_stop) {
      const cp = em.motion_stop_cp_error_m != null ? `, CP error ${fmt(1000 * em.motion_stop_cp_error_m, 1)} mm` : "";
      log(`motion stop (${em.motion_stop_reason || "?"}${cp}) at ${fmt(em.motion_stop_time, 3)} s`, "bad");
    }
    if (!em.motion_stop && pe.motion_stop) log("motion stop released", "ok");
    if (em.fault && em.fault !== pe.fault) log(`FAULT: ${em.fault}`, "bad");
    if (s.fallen && !prev.fallen) log("FALLEN", "bad");
    if (em.flag && !pe.flag) {
      const cp = em.flag_cp_error_m != null ? ` (CP error ${fmt(1000 * em.flag_cp_error_m, 1)} mm)` : "";
      log(`capture-point flag raised${cp} at ${fmt(em.flag_rose_at, 3)} s`, "bad");
    }
    if (s.scene !== prev.scene) log(`scene is now ${s.scene}`, "other");
  }
  updateRuns(s.runs || []);
  updateCommands(s.commands || []);
  updateLock(s.operator_lock);
  plotSample(s);
}
$("latched-ack").addEventListener("click", () => { acknowledged = $("latched").dataset.key; $("latched").hidden = true; });

// what the other clients asked (the console's journal of control requests, `commands` in the state): into the
// history as they come; what was there before this page opened is not replayed
let lastCommandSeq = null;
function updateCommands(commands) {
  const newest = commands.length ? commands[commands.length - 1].seq : 0;
  if (lastCommandSeq === null || newest < lastCommandSeq) { lastCommandSeq = newest; return; }  // (re)started
  for (const c of commands) {
    if (c.seq <= lastCommandSeq || c.client === CLIENT_ID) continue;
    const answer = c.status < 300 ? (c.answer || "ok") : `${c.status} ${c.answer}`;
    log(`${c.client}: ${c.request}${c.body ? " " + c.body : ""} -> ${answer}`, c.status < 300 ? "other" : "bad");
  }
  lastCommandSeq = newest;
}

// ---- behaviours: a button and a generated form per registered behaviour; runs with progress and cancel ------
let behaviors = [];

function rangeText(p) {
  const parts = [];
  if (p.unit && p.unit !== "-") parts.push(`[${p.unit}]`);
  if (p.min !== null && p.min !== undefined && p.max !== null && p.max !== undefined) parts.push(`${p.min} .. ${p.max}`);
  else if (p.min !== null && p.min !== undefined) parts.push(`>= ${p.min}`);
  else if (p.max !== null && p.max !== undefined) parts.push(`<= ${p.max}`);
  if (p.choices) parts.push(p.choices.join(" | "));
  return parts.join(" ");
}

function fieldInput(p, id) {
  if (p.choices) {
    const s = el("select", {id, name: p.name});
    for (const c of p.choices) s.append(el("option", {value: String(c), text: String(c)}));
    s.value = String(p.default);
    return s;
  }
  if (p.type === "boolean") return el("input", {id, name: p.name, type: "checkbox", checked: !!p.default});
  if (p.type === "number" || p.type === "integer") {
    return el("input", {id, name: p.name, type: "number", step: p.type === "integer" ? "1" : "any",
                        min: p.min ?? undefined, max: p.max ?? undefined, value: p.default ?? "", required: true});
  }
  if (p.type === "array") {
    return el("textarea", {id, name: p.name, rows: "3", placeholder: '[{"behavior": "squat", "params": {"depth_m": 0.1}}]'});
  }
  return el("input", {id, name: p.name, type: "text", value: p.default ?? ""});
}

function openForm(b) {
  const f = $("behavior-form");
  f.replaceChildren(el("strong", {class: "span", text: `${b.name}: ${b.summary}`}));
  for (const p of b.params) {
    const id = `bp-${b.name}-${p.name}`;
    f.append(el("label", {for: id, text: p.name, title: p.doc || ""}), fieldInput(p, id),
             el("span", {class: "range", text: rangeText(p), title: p.doc || ""}));
  }
  f.append(el("div", {class: "span row"}, el("button", {type: "submit", text: `Start ${b.name}`}),
              el("button", {type: "button", text: "Close", onclick: () => { f.hidden = true; }})));
  f.dataset.behavior = b.name;
  f.hidden = false;
}

$("behavior-form").addEventListener("submit", (e) => {
  e.preventDefault();
  const b = behaviors.find((x) => x.name === $("behavior-form").dataset.behavior);
  const body = {};
  for (const p of b.params) {
    const input = $(`bp-${b.name}-${p.name}`);
    if (p.type === "boolean") body[p.name] = input.checked;
    else if (p.type === "number") body[p.name] = Number(input.value);
    else if (p.type === "integer") body[p.name] = Math.round(Number(input.value));
    else if (p.type === "array") {
      try { body[p.name] = JSON.parse(input.value || "[]"); } catch (err) { say(`${p.name}: not JSON (${err.message})`, true); return; }
    } else body[p.name] = input.value;
  }
  startBehavior(b.name, body, `${b.name} ${JSON.stringify(body)}`);
});

async function startBehavior(name, body, shown) {
  log(`> ${shown}`, "cmd");
  const d = await post(`/api/behaviors/${name}`, body);
  if (d) { myRuns.add(d.id); log(d.message, "ok"); }
  return d;
}

function updateRuns(runs) {
  const box = $("runs");
  for (const r of runs) {
    const before = knownRuns.get(r.id);
    if (before === undefined && !myRuns.has(r.id)) log(`another client started ${r.behavior} (run ${r.id})`, "other");
    if (before !== r.state && r.state !== "running") {
      const result = r.result && Object.keys(r.result).length ? ` ${JSON.stringify(r.result)}` : "";
      log(`run ${r.id} ${r.behavior} ${r.state}: ${r.message}${result}`, r.state === "succeeded" ? "ok" : "bad");
    }
    knownRuns.set(r.id, r.state);
  }
  const shown = runs.slice(-4);
  const key = JSON.stringify(shown.map((r) => [r.id, r.state, Math.round(100 * r.progress), r.message]));
  if (key === box.dataset.key) return;  // unchanged: not built again
  box.dataset.key = key;
  box.replaceChildren(...shown.map((r) => el("div", {class: "run", "data-run": r.id},
    el("span", {text: `run ${r.id} ${r.behavior}: ${r.state} (${Math.round(100 * r.progress)} %) ${r.message || ""}`}),
    r.state === "running" ? el("button", {type: "button", text: "Cancel",
                                           onclick: () => post(`/api/behaviors/runs/${r.id}/cancel`)}) : el("span"),
    el("progress", {max: "1", value: String(r.progress), "aria-label": `run ${r.id} progress`}))));
}

// ---- the command box: `name v1 v2 ...` (the behaviour's parameters in declaration order) or `name k=v` ------
const BUILTINS = {
  help: () => log("commands: " + behaviors.map((b) => `${b.name} ${b.params.filter((p) => p.type !== "array")
    .map((p) => p.name).join(" ")}`).join("; ") + "; estop; release; stop (motion); cancel [run]. A place's name " +
    "(GET /api/places, e.g. table) stands for the x y z of a point where a behaviour takes one (look_at table)", "ok"),
  estop: () => estop("command"),
  release: () => post("/api/estop/release").then((d) => d && log(d.message, "ok")),
  stop: () => post("/api/motion/stop").then((d) => d && log(d.message, "ok")),
  cancel: (args) => {
    const id = args.length ? Number(args[0]) : [...myRuns].pop();
    if (!Number.isInteger(id)) throw new Error(`cancel: give a run id (got ${args[0]})`);
    return post(`/api/behaviors/runs/${id}/cancel`);
  },
};

function convert(p, text) {
  if (p.type === "number" || p.type === "integer") {
    const v = Number(text);
    if (text === "" || !Number.isFinite(v)) throw new Error(`${p.name}: '${text}' is not a number (${rangeText(p)})`);
    if (p.type === "integer" && !Number.isInteger(v)) throw new Error(`${p.name}: '${text}' is not an integer`);
    if ((p.min !== null && p.min !== undefined && v < p.min) || (p.max !== null && p.max !== undefined && v > p.max)) {
      throw new Error(`${p.name}: ${v} is outside ${rangeText(p)}`);
    }
    return v;
  }
  if (p.type === "boolean") {
    const t = text.toLowerCase();
    if (["true", "1", "yes", "on"].includes(t)) return true;
    if (["false", "0", "no", "off"].includes(t)) return false;
    throw new Error(`${p.name}: '${text}' is not true or false`);
  }
  if (p.choices && !p.choices.map(String).includes(text)) {
    throw new Error(`${p.name}: '${text}' is not one of ${p.choices.join(", ")}`);
  }
  return text;
}

// a named place (GET /api/places/{name}: the scene's known ones, the located objects) for the parameters that say
// which coordinate of a point a place gives (`place`: x, y, z); the error lists the valid names
async function resolvePlace(name) {
  const r = await fetch(`/api/places/${encodeURIComponent(name)}`, {headers: headers(false)});
  const d = await r.json().catch(() => ({}));
  if (!r.ok) throw new Error(typeof d.detail === "string" ? d.detail : `place ${name}: ${r.status}`);
  return d;
}

async function parseCommand(text) {
  const words = text.trim().split(/\s+/).filter(Boolean);
  if (!words.length) throw new Error("type a command (help lists them)");
  const [name, ...args] = words;
  const b = behaviors.find((x) => x.name === name);
  if (!b) {
    throw new Error(`unknown command '${name}'; valid: ${[...behaviors.map((x) => x.name), ...Object.keys(BUILTINS)].join(", ")}`);
  }
  const params = b.params.filter((p) => p.type !== "array");
  const body = {};
  const places = [];  // what each place name stood for, said in the history
  let k = 0;
  for (const a of args) {
    const eq = a.indexOf("=");
    if (eq > 0) {
      const key = a.slice(0, eq);
      const p = b.params.find((x) => x.name === key);
      if (!p) throw new Error(`${name} has no parameter '${key}'; valid: ${b.params.map((x) => x.name).join(", ")}`);
      body[key] = p.type === "array" ? JSON.parse(a.slice(eq + 1)) : convert(p, a.slice(eq + 1));
      continue;
    }
    if (k >= params.length) throw new Error(`${name} takes at most ${params.length} values (${params.map((p) => p.name).join(" ")})`);
    if (params[k].place && !Number.isFinite(Number(a))) {  // a place's name gives the point's coordinates
      const place = await resolvePlace(a);
      const given = [];
      for (; k < params.length && params[k].place; k += 1) {
        body[params[k].name] = place.position_m["xyz".indexOf(params[k].place)];
        given.push(`${params[k].name} ${fmt(body[params[k].name], 3)}`);
      }
      places.push(`${a}: ${place.name} at ${xyz(place.position_m)} m (${place.source}): ${given.join(", ")}`);
      continue;
    }
    body[params[k].name] = convert(params[k], a);
    k += 1;
  }
  return {name, body, places};
}

$("command-form").addEventListener("submit", async (e) => {
  e.preventDefault();
  const text = $("command").value.trim();
  const [word, ...args] = text.split(/\s+/);
  try {
    if (BUILTINS[word]) { log(`> ${text}`, "cmd"); await BUILTINS[word](args); }
    else {
      const {name, body, places} = await parseCommand(text);
      if (places.length) { log(`> ${text}`, "cmd"); for (const p of places) log(p, "ok"); }
      await startBehavior(name, body, places.length ? `${name} ${JSON.stringify(body)}` : text);
    }
    $("command").value = "";
  } catch (err) {
    log(`> ${text}`, "cmd");
    log(err.message, "bad");
    say(err.message, true);
  }
});

// ---- teleoperation: the selected point's twist from two 3-DOF sticks, the gamepad and the keys -------------
// the points in the order they are solved and what each takes: /api/config's `points` (controller.operation.ranges)
let POINTS = [];
let RANGES = {};  // point -> {linear: [3] m/s, angular: [3] deg/s}: |v| allowed per component, 0 where it is unused
const FULL = {  // full deflection: linear [m/s], angular [deg/s]
  rhand: [0.1, 30], lhand: [0.1, 30], head: [0, 30], waist: [0.05, 15], walk: [0.2, 20],
};
const STICK_DEAD_ZONE = 0.08;
const GAMEPAD_DEAD_ZONE = 0.1;
const STREAM_HZ = 50;
const ZERO_TAIL = 3;  // zero setpoints sent after a point's input ends (the stream then goes quiet)
let selected = "rhand";
const onScreen = [[0, 0, 0], [0, 0, 0]];  // per stick: fwd, left, twist in [-1, 1]
let gamepadAxes = [0, 0, 0, 0, 0, 0];
let gamepadDeadman = false;

function selectPoint(p) {
  selected = p;
  for (const b of $("points").children) b.setAttribute("aria-checked", String(b.dataset.point === p));
  setText($("sel-point"), p);
}
function setPoints(ranges) {
  RANGES = ranges;
  POINTS = Object.keys(ranges);
  $("points").replaceChildren(...POINTS.map((p, k) => el("button", {
    type: "button", role: "radio", "data-point": p, "aria-checked": "false", title: `key ${k + 1}`, text: p,
    onclick: () => selectPoint(p)})));
  if (POINTS.length) selectPoint(POINTS.includes(selected) ? selected : POINTS[0]);
}

const clamp1 = (v) => Math.max(-1, Math.min(1, v));
function deadZone(v, dz) { const a = Math.abs(v); return a <= dz ? 0 : Math.sign(v) * (a - dz) / (1 - dz); }

function axes() {
  const a = [0, 0, 0, 0, 0, 0];
  for (let s = 0; s < 2; s++) for (let i = 0; i < 3; i++) a[3 * s + i] += onScreen[s][i];
  if (gamepadDeadman) for (let i = 0; i < 6; i++) a[i] += gamepadAxes[i];
  for (const code of heldKeys) { const [i, sign] = KEY_AXES[code]; a[i] += sign * KEY_DEFLECTION; }
  return a.map(clamp1);
}

function twistOf(point, a) {
  const [lf, ll, lt, rf, rl, rt] = a;
  const [vlin, vang] = FULL[point];
  let lin, ang;
  if (point === "walk") { lin = [lf, 0.5 * ll, 0]; ang = [0, 0, clamp1(lt + rl)]; }
  else if (point === "head") { lin = [0, 0, 0]; ang = [0, clamp1(rf + lf), clamp1(rl + ll)]; }
  else if (point === "waist") { lin = [0, 0, clamp1(lf + lt)]; ang = [rt, rf, rl]; }
  else { lin = [lf, ll, lt]; ang = [rt, rf, rl]; }
  const {linear: lb, angular: ab} = RANGES[point];  // within the point's bounds; 0 on a component it does not use
  const r = (v, b) => Math.round(Math.max(-b, Math.min(b, v)) * 1e4) / 1e4 || 0;
  return {linear: lin.map((v, i) => r(v * vlin, lb[i])), angular: ang.map((v, i) => r(v * vang, ab[i]))};
}
const isZero = (t) => t.linear.every((v) => v === 0) && t.angular.every((v) => v === 0);

// the WS /ws/operator stream: each message answered once, in order (ack or error): the FIFO gives the round trip
let opWs = null;
let opWsLatest = null;  // the newest socket, open or opening
const sentAt = [];
const rtts = [];
const zeroTail = {};
let lastStreamError = "";

function connectOperator() {
  const ws = new WebSocket(wsUrl("/ws/operator"));
  ws.onopen = () => { opWs = ws; sentAt.length = 0; };
  ws.onmessage = (m) => {
    if (m.data.includes('"estop": true')) {
      const rec = estopsOnWs.shift();  // an e-stop's answer: not a setpoint's (no round trip to count)
      try { const d = JSON.parse(m.data); if (rec && rec.reply === null) rec.reply = d; } catch (e) { /* */ }
      return;
    }
    const t0 = sentAt.shift();
    if (t0 !== undefined) {
      rtts.push(performance.now() - t0);
      if (rtts.length > 50) rtts.shift();
    }
    let d = {};
    try { d = JSON.parse(m.data); } catch (e) { return; }
    if (d.ok === false && d.detail !== lastStreamError) {
      lastStreamError = d.detail;
      log(`stream: ${d.detail}`, "bad");
    } else if (d.ok) lastStreamError = "";
  };
  ws.onclose = () => {
    if (opWs === ws) opWs = null;
    estopsOnWs.length = 0;  // answered no more: their POSTs answer them
    setTimeout(connectOperator, ws.renewed ? 0 : 1000);
  };
  opWsLatest = ws;
}
// the lock just taken: the stick stream and the telemetry reconnect at once with its lease token (the holder's
// stream is the one that may steer; an open one keeps the lock)
function renewStreams() {
  for (const ws of [opWsLatest, telemetryWs]) {
    if (ws && ws.readyState <= WebSocket.OPEN) { ws.renewed = true; ws.close(); }
  }
}

function streamTick() {
  readGamepad();  // also here, not only every animation frame: a busy compositor must not delay a let-go dead-man
  const a = axes();
  let sending = false;
  for (const p of POINTS) {
    const t = p === selected ? twistOf(p, a) : {linear: [0, 0, 0], angular: [0, 0, 0]};
    if (!isZero(t)) zeroTail[p] = ZERO_TAIL;
    else if (zeroTail[p] > 0) zeroTail[p] -= 1;
    else continue;
    sending = true;
    if (opWs && opWs.readyState === WebSocket.OPEN && opWs.bufferedAmount < 4096) {
      opWs.send(JSON.stringify({point: p, linear: t.linear, angular: t.angular}));
      sentAt.push(performance.now());
      if (sentAt.length > 200) sentAt.shift();
    }
  }
  setText($("stream-state"), !opWs ? "not connected" : sending ? `streaming ${selected} at ${STREAM_HZ} Hz` : "idle");
  if (rtts.length) {
    const sorted = [...rtts].sort((x, y) => x - y);
    setText($("latency"), `${sorted[Math.floor(sorted.length / 2)].toFixed(1)} ms (median of ${sorted.length})`);
  }
}
setInterval(streamTick, 1000 / STREAM_HZ);
// the page hidden: nothing held any more (the zero tail stops what moved)
document.addEventListener("visibilitychange", () => {
  if (document.hidden) { heldKeys.clear(); for (const s of onScreen) s.fill(0); gamepadDeadman = false; }
});

// on-screen sticks: a pad (fwd, left) and a twist bar each; mouse and touch (pointer events), spring back
function bindStick(root, s) {
  const pad = root.querySelector(".pad"), twist = root.querySelector(".twist");
  const padKnob = pad.querySelector(".knob"), twistKnob = twist.querySelector(".knob");
  function padAt(e) {
    const r = pad.getBoundingClientRect();
    const radius = r.width / 2;
    let dx = (e.clientX - r.left - radius) / radius, dy = (e.clientY - r.top - radius) / radius;
    const n = Math.hypot(dx, dy);
    if (n > 1) { dx /= n; dy /= n; }
    padKnob.style.transform = `translate(${dx * radius}px, ${dy * radius}px)`;
    const m = Math.min(1, Math.hypot(dx, dy));
    const k = m > 0 ? deadZone(m, STICK_DEAD_ZONE) / m : 0;
    onScreen[s][0] = -dy * k;
    onScreen[s][1] = -dx * k;
  }
  function twistAt(e) {
    const r = twist.getBoundingClientRect();
    const half = r.width / 2;
    const dx = Math.max(-1, Math.min(1, (e.clientX - r.left - half) / half));
    twistKnob.style.transform = `translateX(${dx * half}px)`;
    onScreen[s][2] = -deadZone(dx, STICK_DEAD_ZONE);
  }
  function bind(target, at, release) {
    target.addEventListener("pointerdown", (e) => {
      e.preventDefault();
      target.setPointerCapture(e.pointerId);
      root.classList.add("active");
      at(e);
    });
    target.addEventListener("pointermove", (e) => { if (target.hasPointerCapture(e.pointerId)) at(e); });
    for (const ev of ["pointerup", "pointercancel", "lostpointercapture"]) {
      target.addEventListener(ev, () => { root.classList.remove("active"); release(); });
    }
  }
  // let go: the zero goes out at once, not at the next 50 Hz send
  bind(pad, padAt, () => { onScreen[s][0] = onScreen[s][1] = 0; padKnob.style.transform = ""; streamTick(); });
  bind(twist, twistAt, () => { onScreen[s][2] = 0; twistKnob.style.transform = ""; streamTick(); });
}
bindStick($("stick-left"), 0);
bindStick($("stick-right"), 1);

// the Gamepad API, polled every animation frame: sticks = [OP]'s two joysticks, RB/LB held = dead-man
const GP = {estop: 1, nextPoint: 3, deadman: [4, 5], lt: 6, rt: 7, dpadLeft: 14, dpadRight: 15};
let gpPrev = [];
function pollGamepad() {
  const held = gamepadDeadman;
  readGamepad();
  if (held && !gamepadDeadman) streamTick();  // the dead-man let go: the zero goes out at once
  requestAnimationFrame(pollGamepad);
}
function readGamepad() {
  const pads = navigator.getGamepads ? [...navigator.getGamepads()].filter(Boolean) : [];
  const gp = pads.find((g) => g.connected !== false);
  if (gp) {
    const ax = (i) => deadZone(gp.axes[i] || 0, GAMEPAD_DEAD_ZONE);
    const btn = (i) => { const b = gp.buttons[i]; return b ? (typeof b === "object" ? b.value || (b.pressed ? 1 : 0) : b) : 0; };
    const pressed = gp.buttons.map((b, i) => btn(i) > 0.5);
    if (pressed[GP.estop] && !gpPrev[GP.estop]) estop("gamepad");
    if (pressed[GP.nextPoint] && !gpPrev[GP.nextPoint] && POINTS.length) selectPoint(POINTS[(POINTS.indexOf(selected) + 1) % POINTS.length]);
    gpPrev = pressed;
    gamepadDeadman = GP.deadman.some((i) => pressed[i]);
    gamepadAxes = [-ax(1), -ax(0), btn(GP.lt) - btn(GP.rt), -ax(3), -ax(2), btn(GP.dpadLeft) - btn(GP.dpadRight)];
    setText($("gamepad"), `gamepad: ${gp.id || "connected"}; dead-man ${gamepadDeadman ? "HELD" : "released"}`);
  } else {
    gamepadDeadman = false;
  }
}
requestAnimationFrame(pollGamepad);

// ---- controller management: start/stop pairs and parameter panels from the OpenAPI document ----------------
async function buildController(openapi, cfg) {
  const box = $("layer-buttons");
  for (const [path, ops] of Object.entries(openapi.paths || {})) {
    const m = path.match(/^\/api\/(.+)\/start$/);
    if (!m || !ops.post || !(openapi.paths[`/api/${m[1]}/stop`] || {}).post) continue;
    const param = (ops.post.parameters || []).find((p) => p.in === "path");
    const values = param ? ((param.schema || {}).enum || []) : [null];
    for (const v of values) {
      const seg = param ? m[1].replace(`{${param.name}}`, v) : m[1];
      const label = seg.replace(/\//g, " ");
      box.append(el("span", {class: "row"}, el("b", {text: label}),
        el("button", {type: "button", text: "start", "aria-label": `start ${label}`,
                      onclick: () => post(`/api/${seg}/start`).then((d) => d && log(d.message, "ok"))}),
        el("button", {type: "button", text: "stop", "aria-label": `stop ${label}`,
                      onclick: () => post(`/api/${seg}/stop`).then((d) => d && log(d.message, "ok"))})));
    }
  }
  const sel = $("scene");
  for (const name of cfg.scenes || []) sel.append(el("option", {value: name, text: name}));
  const put = (((openapi.paths["/api/params"] || {}).put || {}).requestBody || {}).content;
  const schema = put && put["application/json"] && put["application/json"].schema;
  const current = await api("GET", "/api/params");
  if (!schema || !current) return;
  const panels = $("params");
  for (const [owner, ownerSchema] of Object.entries(schema.properties || {})) {
    if (!current[owner]) continue;
    const grid = el("form", {class: "grid", "data-owner": owner});
    for (const [name, fs] of Object.entries(ownerSchema.properties || {})) {
      const id = `pp-${owner}-${name}`;
      const value = current[owner][name];
      let input;
      if (fs.enum) {
        input = el("select", {id, name});
        for (const c of fs.enum) input.append(el("option", {value: String(c), text: String(c)}));
        input.value = String(value);
      } else if (fs.type === "boolean") input = el("input", {id, name, type: "checkbox", checked: !!value});
      else if (fs.type === "number" || fs.type === "integer") {
        input = el("input", {id, name, type: "number", step: "any", min: fs.minimum, max: fs.maximum,
                             value: Array.isArray(value) ? "" : value});
      } else input = el("input", {id, name, type: "text", value: JSON.stringify(value)});
      const range = [fs.minimum !== undefined && fs.maximum !== undefined ? `${fs.minimum} .. ${fs.maximum}` : "",
                     (fs.description || "").replace(/^[^[]*/, "")].join(" ");
      grid.append(el("label", {for: id, text: name, title: fs.description || ""}), input,
                  el("span", {class: "small", text: range}));
    }
    grid.append(el("button", {type: "submit", text: `Apply ${owner}`}));
    grid.addEventListener("submit", (e) => {
      e.preventDefault();
      const changes = {};
      for (const [name, fs] of Object.entries(ownerSchema.properties || {})) {
        const input = $(`pp-${owner}-${name}`);
        let v;
        if (fs.type === "boolean") v = input.checked;
        else if (fs.enum) v = fs.enum.find((c) => String(c) === input.value);
        else if (fs.type === "number" || fs.type === "integer") { if (input.value === "") continue; v = Number(input.value); }
        else { try { v = JSON.parse(input.value); } catch (err) { v = input.value; } }
        if (JSON.stringify(v) !== JSON.stringify(current[owner][name])) changes[name] = v;
      }
      if (!Object.keys(changes).length) { say(`${owner}: nothing changed`); return; }
      api("PUT", "/api/params", {[owner]: changes}).then((d) => {
        if (d) { Object.assign(current[owner], changes); log(`${owner} parameters set: ${JSON.stringify(changes)}`, "ok"); }
      });
    });
    panels.append(el("details", {}, el("summary", {text: `${owner} parameters`}), grid));
  }
}

$("reset-form").addEventListener("submit", (e) => {
  e.preventDefault();
  log(`> reset ${$("scene").value}`, "cmd");
  post("/api/sim/reset", {scene: $("scene").value}).then((d) => d && log(d.message, "ok"));
});
$("params-dump").addEventListener("click", async () => {
  const d = await api("GET", "/api/params");
  if (!d) return;
  const a = el("a", {href: URL.createObjectURL(new Blob([JSON.stringify(d, null, 2)], {type: "application/json"})),
                     download: "hrp2_params.json"});
  document.body.append(a);
  a.click();
  a.remove();
  log("parameters dumped to hrp2_params.json", "ok");
});
$("params-load").addEventListener("change", async (e) => {
  const file = e.target.files[0];
  if (!file) return;
  let doc;
  try { doc = JSON.parse(await file.text()); } catch (err) { say(`${file.name}: not JSON (${err.message})`, true); return; }
  const d = await api("PUT", "/api/params", doc);
  if (d) log(`parameters loaded from ${file.name} (${Object.keys(doc).join(", ")})`, "ok");
  e.target.value = "";
});

// ---- joint form (the sequence player) ---------------------------------------------------------------------
let limits = {};
$("joint").addEventListener("change", () => {
  const lim = limits[$("joint").value];
  if (lim) { $("angle").min = lim[0]; $("angle").max = lim[1]; $("angle").title = `range ${lim[0]} .. ${lim[1]} deg`; }
});
$("joint-form").addEventListener("submit", (e) => {
  e.preventDefault();
  const angles = {[$("joint").value]: Number($("angle").value)};
  post("/api/sequence/joint-angles", {angles_deg: angles, time: Number($("duration").value)});
});

// ---- the operator lock: who holds it, shown to all; a watcher's controls greyed out (E-STOP never) -----------
let lockHolder = null;
function updateLock(lock) {
  const holder = lock ? lock.holder : null;
  const mine = holder === CLIENT_ID && lockToken !== null;
  const watching = holder !== null && !mine;
  const st = $("lock-state");
  setText(st, holder === null ? "control: free (anyone)" : mine ? "control: YOU" : `control: ${holder} (watching)`);
  setClass(st, holder === null ? "" : mine ? "mine" : "other");
  setText($("lock-btn"), mine ? "Release control" : "Take control");
  const title = mine ? "Give the operator lock back: any client may control again"
    : watching ? `${holder} holds control; taking it is refused until they release it or leave`
    : "Take the operator lock: the others can only watch (and press E-STOP)";
  if ($("lock-btn").title !== title) $("lock-btn").title = title;
  if (watching !== document.body.classList.contains("watching")) {
    document.body.classList.toggle("watching", watching);
    for (const sec of document.querySelectorAll("#controls > section")) sec.inert = watching;
    for (const b of document.querySelectorAll(".stop .rel, #walk-estop, #st-stop")) b.disabled = watching;
    $("camera-popups").inert = watching;
    if (watching) log(`${holder} took control: this page watches (E-STOP stays available)`, "other");
    else if (lockHolder !== null && lockHolder !== CLIENT_ID) log("control is free again", "other");
  }
  lockHolder = holder;
}
$("lock-btn").addEventListener("click", async () => {
  if (lockHolder === CLIENT_ID && lockToken !== null) {
    const d = await api("DELETE", "/api/operator/lock");
    if (d) { lockToken = null; log("control released", "ok"); }
  } else {
    const d = await post("/api/operator/lock", {client: CLIENT_ID});
    if (d && d.token) {
      lockToken = d.token;
      renewStreams();
      updateLock(d);
      log("you have control", "ok");
    }
  }
});

// ---- the wide head camera (WS /ws/camera: meta, then the JPEG) and the recognitions over it ----------------
const CAMERA_HZ = 12;  // asked of the stream: a little over the 10 Hz the view must keep
window.hrp2Camera = {frames: 0, seq: null, meta: null, src: null};  // src: the frame on screen (the next may load)
const cameraTimes = [];
let cameraWs = null;
// One frame decodes at a time and the newest waiting one follows it: a frame set while the previous was still
// loading replaced it, and on a loaded machine (frames every 83 ms, a decode slower than that) the image could
// stay blank. A frame counts (frames, seq, rate) when it is on screen, with the recognitions of its meta.
let cameraLoading = false;
let cameraNext = null;  // {blob, meta}: the newest frame received while one was loading
function showCameraFrame(blob, meta) {
  if (cameraLoading) { cameraNext = {blob, meta}; return; }
  cameraLoading = true;
  const img = $("camera-img");
  const old = img.src;
  const shown = (ok) => {
    img.onload = img.onerror = null;
    if (old.startsWith("blob:")) URL.revokeObjectURL(old);
    cameraLoading = false;
    if (ok) {
      const cam = window.hrp2Camera;
      cam.frames += 1;
      cam.seq = meta ? meta.seq : null;
      cam.src = img.src;
      cam.meta = meta;
      const now = performance.now();
      cameraTimes.push(now);
      while (cameraTimes.length && cameraTimes[0] < now - 2000) cameraTimes.shift();
      const hz = cameraTimes.length > 1 ? 1000 * (cameraTimes.length - 1) / (now - cameraTimes[0]) : 0;
      setText($("camera-info"), `wide head camera 93.6 x 70.8 deg: ${hz.toFixed(1)} Hz` +
        (meta ? `, t ${fmt(meta.time_s, 2)} s` : ""));
      if (meta) drawRecognitions(meta);
    }
    if (cameraNext) { const n = cameraNext; cameraNext = null; showCameraFrame(n.blob, n.meta); }
  };
  img.onload = () => shown(true);
  img.onerror = () => shown(false);
  img.src = URL.createObjectURL(blob);
}
function startCamera() {
  if (cameraWs || document.hidden) return;  // a hidden page watches nothing: the console renders for no one
  let ws;
  try { ws = new WebSocket(wsUrl(`/ws/camera?rate_hz=${CAMERA_HZ}`)); } catch (e) { return; }
  cameraWs = ws;
  ws.binaryType = "blob";
  let meta = null;
  ws.onmessage = (m) => {
    if (typeof m.data === "string") {
      let d = {};
      try { d = JSON.parse(m.data); } catch (e) { return; }
      if (d.ok && d.seq !== undefined) meta = d;
      else if (d.ok === false) setText($("camera-info"), `wide head camera: ${d.detail}`);
      return;
    }
    showCameraFrame(m.data, meta);
  };
  ws.onclose = () => { if (cameraWs === ws) cameraWs = null; setTimeout(startCamera, 1000); };
}
document.addEventListener("visibilitychange", () => {
  if (document.hidden && cameraWs) { const ws = cameraWs; cameraWs = null; ws.close(); }
  else if (!document.hidden) startCamera();
});

const popups = new Map();  // object name -> {box, pop, key, editing}
const xyz = (p) => `(${p.map((v) => fmt(v, 3)).join(", ")})`;
function drawRecognitions(meta) {
  const layer = $("camera-popups");
  const scale = $("camera-img").clientWidth / (meta.width || 320);
  const seen = new Set();
  let stacked = 0;
  for (const r of meta.recognitions || []) {
    seen.add(r.name);
    let p = popups.get(r.name);
    if (!p) {
      p = {box: el("div", {class: "rec-box"}), pop: el("div", {class: "rec-pop", role: "dialog",
                                                               "aria-label": `recognition of ${r.name}`}),
           key: null, editing: false};
      layer.append(p.box, p.pop);
      popups.set(r.name, p);
    }
    const status = r.status || "estimated";
    setClass(p.box, `rec-box ${status}`);
    setClass(p.pop, `rec-pop ${status}`);
    const key = JSON.stringify([r.position_m, status, r.time_s]);
    if (key !== p.key && !p.editing) {
      if (p.key === null || JSON.parse(p.key)[2] !== r.time_s) {  // a new recognition: into the history too
        log(`recognition: ${r.name} at ${xyz(r.position_m)} m (${status}); confirm or correct it over the camera view`,
            "other");
      }
      p.key = key;
      renderPopup(p, r, status);
    }
    if (r.box_px) {
      const [u0, v0, u1, v1] = r.box_px.map((v) => v * scale);
      Object.assign(p.box.style, {left: `${u0}px`, top: `${v0}px`, width: `${u1 - u0}px`, height: `${v1 - v0}px`,
                                  display: "block"});
      Object.assign(p.pop.style, {left: `${Math.min(u1 + 4, 320 - 40)}px`, top: `${Math.max(0, v0 - 10)}px`});
    } else {
      p.box.style.display = "none";
      Object.assign(p.pop.style, {left: "4px", top: `${4 + 44 * stacked++}px`});
    }
  }
  for (const [name, p] of popups) {
    if (!seen.has(name)) { p.box.remove(); p.pop.remove(); popups.delete(name); }
  }
}
function renderPopup(p, r, status) {
  const sigma = r.sigma_m ? Math.hypot(r.sigma_m[0], r.sigma_m[1]) * 1000 : null;
  const text = `${r.name} at ${xyz(r.position_m)} m` + (sigma !== null ? `, sigma ${fmt(sigma, 1)} mm` : "") +
    (r.box_px ? "" : " (out of view)") + ` - ${status}`;
  const confirm = el("button", {type: "button", text: "Confirm", onclick: async () => {
    const d = await post(`/api/recognitions/${r.name}/confirm`, {});
    if (d) log(d.message, "ok");
  }});
  const form = el("form", {hidden: true, "aria-label": `corrected position of ${r.name}`});
  const inputs = ["x", "y", "z"].map((axis, i) => el("input", {type: "number", step: "any", min: -20, max: 20,
    value: r.position_m[i], "aria-label": `${r.name} ${axis} [m]`, required: true}));
  form.append(...inputs, el("button", {type: "submit", text: "Send"}));
  form.addEventListener("submit", async (e) => {
    e.preventDefault();
    const d = await post(`/api/recognitions/${r.name}/correct`, {position_m: inputs.map((x) => Number(x.value))});
    if (d) { log(d.message, "ok"); p.editing = false; form.hidden = true; }
  });
  const correct = el("button", {type: "button", text: "Correct", onclick: () => {
    p.editing = form.hidden;
    form.hidden = !form.hidden;
    if (!form.hidden) inputs[0].focus();
  }});
  p.pop.replaceChildren(el("div", {text}), confirm, correct, form);
}

// ---- plots from the telemetry: ZMP and COG x / y, the feet's vertical forces (>= 20 Hz, last 10 s) -----------
const PLOT_WINDOW_S = 10;
class TimePlot {
  constructor(canvas, legend, series, unit, digits) {
    this.canvas = canvas; this.legend = legend; this.series = series; this.unit = unit; this.digits = digits;
    this.t = []; this.v = series.map(() => []);
    this.draws = 0;  // redraws (the browser test reads it)
    this.samples = 0;  // samples received
  }
  push(t, values) {
    if (this.t.length && t < this.t[this.t.length - 1]) { this.t = []; this.v = this.series.map(() => []); }  // a reset
    if (this.t.length && t === this.t[this.t.length - 1]) return;
    this.t.push(t);
    this.samples += 1;
    values.forEach((x, i) => this.v[i].push(x));
    while (this.t.length && this.t[0] < t - PLOT_WINDOW_S) { this.t.shift(); this.v.forEach((a) => a.shift()); }
    this.dirty = true;
  }
  draw() {
    if (!this.dirty) return;
    this.dirty = false;
    this.draws += 1;
    const c = this.canvas, g = c.getContext("2d"), W = c.width, H = c.height, pad = 4;
    g.clearRect(0, 0, W, H);
    if (this.t.length < 2) return;
    let lo = Infinity, hi = -Infinity;
    for (const a of this.v) for (const x of a) if (Number.isFinite(x)) { lo = Math.min(lo, x); hi = Math.max(hi, x); }
    if (!Number.isFinite(lo)) return;
    const span = Math.max(hi - lo, this.unit === "N" ? 20 : 0.02);
    const mid = (hi + lo) / 2;
    lo = mid - 0.55 * span; hi = mid + 0.55 * span;
    const t1 = this.t[this.t.length - 1], t0 = t1 - PLOT_WINDOW_S;
    const X = (t) => pad + (W - 2 * pad) * (t - t0) / PLOT_WINDOW_S, Y = (x) => H - pad - (H - 2 * pad) * (x - lo) / (hi - lo);
    g.strokeStyle = "#d8dce2"; g.lineWidth = 1;
    g.beginPath(); g.moveTo(pad, Y(mid)); g.lineTo(W - pad, Y(mid)); g.stroke();
    g.fillStyle = "#666"; g.font = "10px sans-serif";
    g.fillText(`${hi.toFixed(this.digits)} ${this.unit}`, pad + 2, 11);
    g.fillText(`${lo.toFixed(this.digits)} ${this.unit}`, pad + 2, H - 6);
    this.series.forEach((s, i) => {
      g.strokeStyle = s.color; g.lineWidth = 1.5; g.beginPath();
      let started = false;
      this.t.forEach((t, k) => {
        const x = this.v[i][k];
        if (!Number.isFinite(x)) { started = false; return; }
        if (started) g.lineTo(X(t), Y(x)); else { g.moveTo(X(t), Y(x)); started = true; }
      });
      g.stroke();
    });
    if (this.legend.children.length !== this.series.length + 1) {
      this.legend.replaceChildren(...this.series.map((s) => el("span", {style: `color:${s.color}; margin-right: 0.8em`})),
                                  el("span"));
    }
    this.series.forEach((s, i) => {
      setText(this.legend.children[i], `${s.label} ${fmt(this.v[i][this.v[i].length - 1], this.digits)} ${this.unit}`);
    });
    setText(this.legend.children[this.series.length], `t ${fmt(t1, 2)} s`);
  }
}
const PLOTS = {
  x: new TimePlot($("plot-x"), $("legend-x"), [{label: "ZMP x", color: "#1f9e3a"}, {label: "COG x", color: "#e07b00"}], "m", 3),
  y: new TimePlot($("plot-y"), $("legend-y"), [{label: "ZMP y", color: "#1f9e3a"}, {label: "COG y", color: "#e07b00"}], "m", 3),
  f: new TimePlot($("plot-f"), $("legend-f"), [{label: "right foot Fz", color: "#c8102e"}, {label: "left foot Fz", color: "#1c6fd1"}], "N", 0),
};
window.hrp2Plots = PLOTS;
function plotSample(s) {
  const zmp = s.zmp || [], cog = s.cog || [], f = s.foot_forces_n || {};
  PLOTS.x.push(s.time, [zmp[0], cog[0]]);
  PLOTS.y.push(s.time, [zmp[1], cog[1]]);
  PLOTS.f.push(s.time, [f.rleg, f.lleg]);
}
function drawPlots() {
  for (const p of Object.values(PLOTS)) p.draw();
  requestAnimationFrame(drawPlots);
}
requestAnimationFrame(drawPlots);

// ---- start-up ---------------------------------------------------------------------------------------------
// The 3D view is viser's client served by this console at /viewer/ with one script added (static/viewer_keys.js)
// that hands Esc / Space and the teleoperation keys to this page. It is loaded from the other loopback name when
// there is one (127.0.0.1 <-> localhost): another site, so the browser runs it in its own process and a slow
// (software) WebGL frame never holds up this page's e-stop.
function viewerHost() {
  return {"127.0.0.1": "localhost", "localhost": "127.0.0.1"}[location.hostname] || location.hostname;
}
let viewerFrame = null;
function mountViewer(cfg) {
  const view = $("view");
  if (!cfg.viewer_port) {
    view.append(el("p", {class: "noviewer", text: "No 3D viewer (started with --headless)."}));
    return;
  }
  const host = viewerHost();
  const shownHost = host.includes(":") ? `[${host}]` : host;
  const ws = `${location.protocol === "https:" ? "wss" : "ws"}://${shownHost}:${cfg.viewer_port}`;
  const origin = `${location.protocol}//${shownHost}${location.port ? ":" + location.port : ""}`;
  viewerFrame = el("iframe", {title: "3D view of the robot (viser)",
                              src: `${origin}/viewer/?websocket=${encodeURIComponent(ws)}`});
  view.append(viewerFrame);
}
window.addEventListener("message", (e) => {
  if (!viewerFrame || e.source !== viewerFrame.contentWindow) return;
  const d = e.data || {};
  if (d.type !== "hrp2-key" || typeof d.code !== "string") return;
  const ev = {key: String(d.key), code: d.code, repeat: !!d.repeat, target: null, ctrlKey: false, metaKey: false,
              altKey: false, preventDefault() {}, stopPropagation() {}};
  if (d.down) onKeyDown(ev); else onKeyUp(ev);
});
window.addEventListener("blur", () => {
  // the focus went into the 3D view (or away): the keys held here are released
  heldKeys.clear();
});

async function start() {
  const cfg = await api("GET", "/api/config") || {};
  doorPort = cfg.estop_port || null;
  connectDoor();
  setPoints(cfg.points || {});
  limits = cfg.joint_limits_deg || {};
  for (const name of cfg.joints || []) $("joint").append(el("option", {value: name, text: name}));
  if (cfg.joints && cfg.joints.includes("RARM_JOINT0")) { $("joint").value = "RARM_JOINT0"; $("joint").dispatchEvent(new Event("change")); }
  mountViewer(cfg);
  behaviors = await api("GET", "/api/behaviors") || [];
  $("behaviors").replaceChildren(...behaviors.map((b) => el("button", {type: "button", text: b.name, title: b.summary,
                                                                        "data-behavior": b.name, onclick: () => openForm(b)})));
  const openapi = await api("GET", "/openapi.json");
  if (openapi) await buildController(openapi, cfg);
}

startTelemetry();
connectOperator();
startCamera();
start().catch((e) => say(`start-up: ${e}`, true));
