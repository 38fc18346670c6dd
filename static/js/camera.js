// The wide head camera (WS /ws/camera: meta, then the JPEG) and the recognitions drawn over it, each with a popup
// to confirm or correct it (camera_popups.js).
import {wsUrl} from "./api.js";
import {drawRecognitions, watchFrameSize} from "./camera_popups.js";
import {$, fmt, setText} from "./dom.js";

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
let watching = false;
export function startCamera() {
  if (!watching) { watching = true; watchFrameSize(); }
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
