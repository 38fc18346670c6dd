// The operator console page: safety bar, telemetry, teleoperation (sticks, gamepad, keys), behaviours, command
// box, controller management. Everything it offers comes from the API's own documents (GET /api/behaviors, the
// OpenAPI schema of PUT /api/params, /api/config): nothing here is written per behaviour or per parameter.
// This entry wires the parts in js/; the E-STOP (js/estop.js) is loaded before it, on its own.
import {api, say} from "./js/api.js";
import {loadBehaviors, updateRuns} from "./js/behaviours.js";
import {startCamera} from "./js/camera.js";
import {buildController, setJoints} from "./js/controller.js";
import {commandsInWords, runsInWords, stopsInWords} from "./js/dialogue.js";
import {$, el} from "./js/dom.js";
import {estopKey, openDoor} from "./js/estop.js";
import {updateLock} from "./js/lock.js";
import {watchLink} from "./js/link.js";
import {plotSample} from "./js/plots.js";
import {readState, startTelemetry} from "./js/state.js";
import {connectOperator, onKeyDown, onKeyUp, setPoints, showLimited} from "./js/sticks.js";

// what each state from the telemetry updates besides the safety bar and the readouts, in this order
readState(showLimited, (s) => updateRuns(s.runs || []), stopsInWords, (s) => runsInWords(s.runs || []),
          (s) => commandsInWords(s.commands || []), (s) => updateLock(s.operator_lock), plotSample);

// ---- the 3D view --------------------------------------------------------------------------------------------
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
  if (!d.down) onKeyUp(ev);
  else if (!estopKey(ev)) onKeyDown(ev);
});

// ---- start-up ---------------------------------------------------------------------------------------------
async function start() {
  const cfg = await api("GET", "/api/config") || {};
  openDoor(cfg.estop_port);
  setPoints(cfg.points || {});
  setJoints(cfg);
  mountViewer(cfg);
  await loadBehaviors();
  const openapi = await api("GET", "/openapi.json");
  if (openapi) await buildController(openapi, cfg);
}

startTelemetry();
watchLink();
connectOperator();
startCamera();
start().catch((e) => say(`start-up: ${e}`, true));
