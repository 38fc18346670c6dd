// The E-STOP: the button (pointer-down), Space / Esc anywhere, and the three ways a press goes out (the e-stop's
// own door into the robot process, the stick stream, a POST), with the page's token and client id it needs.
// The page loads it first, as a script of its own, and it imports nothing: it works whatever else failed to load.

// ---- the token, the client id and the lock's lease (contract with the API): kept in memory only --------------
export const TOKEN = new URLSearchParams(location.search).get("token");
if (TOKEN) history.replaceState(null, "", location.pathname);  // not left in the address bar
// this page's display name (it proves nothing): the one the operator chose for this tab (js/dialogue.js's setting,
// kept in the tab's session storage), else a random one
const NAME_KEY = "hrp2.displayName";
const NAME_RULE = /^[A-Za-z0-9._:-]{1,64}$/;  // the API's client id (app/console/operator_lock.py)
// why `name` cannot be a display name, naming the field and what is allowed; "" when it can
export function checkDisplayName(name) {
  if (typeof name !== "string" || name.length < 1 || name.length > 64) {
    return `display name: ${name.length} characters; 1 to 64 allowed`;
  }
  const bad = [...name].find((c) => !NAME_RULE.test(c));
  if (bad !== undefined) return `display name: '${bad}' is not allowed; only A-Z a-z 0-9 . _ : -`;
  return "";
}
function storedName() {
  try { const n = sessionStorage.getItem(NAME_KEY); return n && !checkDisplayName(n) ? n : null; } catch (e) { return null; }
}
export let CLIENT_ID = storedName() || "page-" + Math.random().toString(36).slice(2, 10);
export function setClientId(name) {
  CLIENT_ID = name;
  try { sessionStorage.setItem(NAME_KEY, name); } catch (e) { /* kept for this page only */ }
}
export let lockToken = null;  // the operator lock's lease token while this page holds it: secret, never shown or logged
export function setLockToken(token) { lockToken = token; }

export function headers(json = true) {
  const h = {"X-Client-Id": CLIENT_ID};
  if (json) h["Content-Type"] = "application/json";
  if (TOKEN) h["Authorization"] = `Bearer ${TOKEN}`;
  if (lockToken) h["X-Lock-Token"] = lockToken;
  return h;
}

// the history's writer (api.js hands it over); without it a press still goes out, unlogged
let log = () => {};
export function logTo(writer) { log = writer; }

// the stick stream's socket while it is open (sticks.js keeps it) and the e-stops sent on it, answered in order
export const stickStream = {ws: null, pending: []};

// ---- E-STOP: pointer-down (not click: no waiting for the release), Space / Esc anywhere, gamepad B ----------
let lastEstopAt = -1e9;
// the e-stops this page sent: input event time (epoch [ms]) and the loop's reply (the e-stop benchmark reads it)
window.hrp2Estops = [];
let presses = 0;
export function estop(source, eventTimeStamp) {
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
  const opWs = stickStream.ws;
  if (opWs && opWs.readyState === WebSocket.OPEN) {
    stickStream.pending.push(record);
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
const button = document.getElementById("estop");
button.addEventListener("pointerdown", (e) => { e.preventDefault(); estop("button", e.timeStamp); });

// The e-stop's own door (GET /api/config's estop_port): a socket to the robot process itself, served between its
// ticks; kept open, reopened when it closes. Without it (no port, or not reachable) the other two ways remain.
let doorWs = null;
let doorPort = null;
const estopsOnDoor = [];  // the e-stops sent on the door, answered in order
export function openDoor(port) {
  doorPort = port || null;
  connectDoor();
}
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
button.addEventListener("click", () => { if (performance.now() - lastEstopAt > 500) estop("button"); });

export function isTyping(target) {
  if (!target || !target.tagName) return false;
  const tag = target.tagName.toUpperCase();
  if (tag === "TEXTAREA" || target.isContentEditable) return true;
  if (tag !== "INPUT") return false;
  return !["button", "checkbox", "radio", "range", "submit", "reset", "file", "color"].includes(
    (target.type || "text").toLowerCase());
}

// Esc or Space, from this page or forwarded from the 3D view: true when the key is the e-stop's (it then goes
// no further, a typed one included)
export function estopKey(e) {
  if (e.key !== "Escape" && e.code !== "Space" && e.key !== " ") return false;
  if (isTyping(e.target)) return true;
  e.preventDefault();
  e.stopPropagation();
  if (!e.repeat) estop(e.key === "Escape" ? "Esc" : "Space");
  return true;
}
window.addEventListener("keydown", estopKey, true);
