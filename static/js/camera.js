// The wide head camera (WS /ws/camera: meta, then the JPEG) and the recognitions drawn over it, each with a popup
// to confirm or correct it.
import {log, post, wsUrl} from "./api.js";
import {$, el, fmt, setClass, setText, xyz} from "./dom.js";

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
export function startCamera() {
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
