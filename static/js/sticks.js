// Teleoperation: the selected point's twist from two 3-DOF on-screen sticks, the gamepad and the held keys (each a
// dead-man: let go, the zero goes out at once), streamed at 50 Hz on WS /ws/operator.
import {log, wsUrl} from "./api.js";
import {$, el, setClass, setText} from "./dom.js";
import {estop, isTyping, stickStream} from "./estop.js";

// ---- keys (Esc and Space are the E-STOP's: estop.js) ----------------------------------------------------------
const KEY_AXES = {  // held keys -> (axis, sign); axes: L fwd, L left, L twist, R fwd, R left, R twist
  KeyW: [0, 1], KeyS: [0, -1], KeyA: [1, 1], KeyD: [1, -1], KeyQ: [2, 1], KeyE: [2, -1],
  ArrowUp: [3, 1], ArrowDown: [3, -1], ArrowLeft: [4, 1], ArrowRight: [4, -1], KeyZ: [5, 1], KeyC: [5, -1],
};
const KEY_DEFLECTION = 0.5;
const heldKeys = new Set();

export function onKeyDown(e) {
  if (isTyping(e.target) || e.ctrlKey || e.metaKey || e.altKey) return;
  if (/^Digit[1-9]$/.test(e.code)) {
    const k = Number(e.code.slice(5)) - 1;
    if (k < POINTS.length) { selectPoint(POINTS[k]); e.preventDefault(); }
    return;
  }
  if (KEY_AXES[e.code]) { heldKeys.add(e.code); e.preventDefault(); }
}
export function onKeyUp(e) {
  // a teleoperation key let go: the zero goes out at once, not at the next 50 Hz send (as a stick's)
  if (heldKeys.delete(e.code)) streamTick();
}
window.addEventListener("keydown", onKeyDown, true);
window.addEventListener("keyup", onKeyUp, true);
// the focus went into the 3D view (or away): the keys held here are released
window.addEventListener("blur", () => heldKeys.clear());

// ---- the points: the selected one's twist from the sticks, the gamepad and the keys ------------------------
// the points in the order they are solved and what each takes: /api/config's `points` (controller.operation.ranges)
let POINTS = [];
let RANGES = {};  // point -> {linear: [3] m/s, angular: [3] deg/s}: |v| allowed per component, 0 where it is unused
const FULL = {  // full deflection: linear [m/s], angular [deg/s]
  rhand: [0.1, 30], lhand: [0.1, 30], head: [0, 30], waist: [0.05, 15], walk: [0.2, 20], rfoot: [0.05, 0], lfoot: [0.05, 0],
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
export function setPoints(ranges) {
  RANGES = ranges;
  POINTS = Object.keys(ranges);
  $("points").replaceChildren(...POINTS.map((p, k) => el("button", {
    type: "button", role: "radio", "data-point": p, "aria-checked": "false", title: `key ${k + 1}`, text: p,
    onclick: () => selectPoint(p)})));
  if (POINTS.length) selectPoint(POINTS.includes(selected) ? selected : POINTS[0]);
}
// the state's word on the selected point: limited by what (a reach, a joint limit), or not
export function showLimited(s) {
  const op = s.operation && s.operation.points && s.operation.points[selected];
  const limited = op ? op.limited : null;
  setText($("limited"), limited || "no");
  setClass($("limited"), limited ? "alarm" : "");
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

// ---- the WS /ws/operator stream: each message answered once, in order (ack or error): the FIFO gives the round
// trip; while open, the E-STOP sends its presses on it too (stickStream)
export let opWsLatest = null;  // the newest socket, open or opening
const sentAt = [];  // per setpoint sent, in order: {t: performance.now(), letGo: the point it let go of, or null}
const rtts = [];
const zeroTail = {};
const moving = {};  // point -> the last twist sent for it was not zero
// the newest let-go (a point's first zero after it moved): sent when, answered when, the robot's answer (the tick
// and control time it applied the zero); the page's tests time the dead-man with it
window.hrp2LetGo = null;
let lastStreamError = "";

export function connectOperator() {
  const ws = new WebSocket(wsUrl("/ws/operator"));
  ws.onopen = () => { stickStream.ws = ws; sentAt.length = 0; };
  ws.onmessage = (m) => {
    if (m.data.includes('"estop": true')) {
      const rec = stickStream.pending.shift();  // an e-stop's answer: not a setpoint's (no round trip to count)
      try { const d = JSON.parse(m.data); if (rec && rec.reply === null) rec.reply = d; } catch (e) { /* */ }
      return;
    }
    const sent = sentAt.shift();
    const now = performance.now();
    if (sent !== undefined) {
      rtts.push(now - sent.t);
      if (rtts.length > 50) rtts.shift();
    }
    let d = {};
    try { d = JSON.parse(m.data); } catch (e) { return; }
    if (sent && sent.letGo) window.hrp2LetGo = {point: sent.letGo, sent_ms: sent.t, answered_ms: now, reply: d};
    if (d.ok === false && d.detail !== lastStreamError) {
      lastStreamError = d.detail;
      log(`stream: ${d.detail}`, "bad");
    } else if (d.ok) lastStreamError = "";
  };
  ws.onclose = () => {
    if (stickStream.ws === ws) stickStream.ws = null;
    stickStream.pending.length = 0;  // answered no more: their POSTs answer them
    setTimeout(connectOperator, ws.renewed ? 0 : 1000);
  };
  opWsLatest = ws;
}

function streamTick() {
  readGamepad();  // also here, not only every animation frame: a busy compositor must not delay a let-go dead-man
  const a = axes();
  const opWs = stickStream.ws;
  let sending = false;
  for (const p of POINTS) {
    const t = p === selected ? twistOf(p, a) : {linear: [0, 0, 0], angular: [0, 0, 0]};
    if (!isZero(t)) zeroTail[p] = ZERO_TAIL;
    else if (zeroTail[p] > 0) zeroTail[p] -= 1;
    else continue;
    sending = true;
    if (opWs && opWs.readyState === WebSocket.OPEN && opWs.bufferedAmount < 4096) {
      opWs.send(JSON.stringify({point: p, linear: t.linear, angular: t.angular}));
      const letGo = moving[p] && isZero(t);
      moving[p] = !isZero(t);
      sentAt.push({t: performance.now(), letGo: letGo ? p : null});
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

// ---- on-screen sticks: a pad (fwd, left) and a twist bar each; mouse and touch (pointer events), spring back --
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

// ---- the Gamepad API, polled every animation frame: sticks = [OP]'s two joysticks, RB/LB held = dead-man -----
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
