// Preview before motion (MoveIt's plan preview, mc_rtc's step-by-step FSM): a behaviour that moves the robot is
// previewed from its own plan (POST /api/behaviors/{name}/preview: footsteps and hand paths, drawn as a ghost in
// the 3D view), then Run, Step (one phase, then it waits: POST /api/behaviors/runs/{id}/step) or Cancel.
// "Confirm moves" (kept in this browser) makes the form's Start and the command box preview first; off, they run
// at once as before (scripts and HTTP never need a confirmation).
import {api, log, post} from "./api.js";
import {$, el, setText} from "./dom.js";

export const MOVERS = new Set(["walk_to", "approach_table", "take_can", "throw_can", "reach", "squat"]);
const CONFIRM_KEY = "hrp2-confirm-moves";
const POLL_MS = 500;

let current = null;  // {name, body, start, runId}

export const confirmMoves = () => localStorage.getItem(CONFIRM_KEY) === "1";

function panel() {
  let p = $("preview");
  if (!p) {
    p = el("section", {id: "preview", class: "preview", hidden: true, "aria-label": "motion preview"});
    $("behavior-form").after(p);
  }
  return p;
}

// the "Confirm moves" switch beside the behaviour buttons
export function confirmSwitch() {
  const box = el("input", {type: "checkbox", id: "confirm-moves", checked: confirmMoves()});
  box.addEventListener("change", () => localStorage.setItem(CONFIRM_KEY, box.checked ? "1" : "0"));
  return el("label", {class: "confirm-moves", for: "confirm-moves",
                      title: "preview a behaviour that moves the robot before it runs"}, box, " Confirm moves");
}

// Start a behaviour, or (a mover, confirmation asked) preview it first; `start(name, body, shown, mode)` runs it.
export function startOrPreview(name, body, shown, start) {
  if (MOVERS.has(name) && confirmMoves()) return showPreview(name, body, shown, start);
  return start(name, body, shown);
}

function describe(d) {
  const hands = d.hand_paths.map((h) => h.hand);
  const phases = d.phases.map((p) => p.phase).join(" → ");
  return `${d.behavior}: ${Math.max(0, d.footsteps.length - 1)} footsteps, ${hands.length} path(s)` +
    `${hands.length ? ` (${[...new Set(hands)].join(", ")})` : ""}${phases ? `; phases: ${phases}` : ""}` +
    `${d.complete ? "" : `. ${d.ends}`}`;
}

export async function showPreview(name, body, shown, start) {
  const d = await post(`/api/behaviors/${name}/preview`, body);
  if (!d) return null;
  current = {name, body, shown, start, runId: null};
  const p = panel();
  p.replaceChildren(
    el("strong", {text: "Preview (ghost in the 3D view)"}),
    el("p", {class: "preview-text", text: describe(d)}),
    el("div", {class: "row"},
       el("button", {type: "button", id: "preview-run", text: "Run", onclick: run}),
       el("button", {type: "button", id: "preview-step", text: "Step", onclick: step,
                     title: "run one phase, then wait for the next Step"}),
       el("button", {type: "button", id: "preview-cancel", text: "Cancel", onclick: cancel})));
  p.hidden = false;
  log(`preview ${describe(d)}`, "ok");
  return d;
}

function close() {
  current = null;
  panel().hidden = true;
  api("DELETE", "/api/behaviors/preview");
}

async function run() {
  if (!current) return;
  const c = current;  // (disabled once stepping)
  close();
  await c.start(c.name, c.body, c.shown);
}

async function step() {
  if (!current) return;
  if (current.runId === null) {
    const d = await current.start(current.name, current.body, `${current.shown} (step mode)`, "step");
    if (!d) return;
    current.runId = d.id;
    $("preview-run").disabled = true;
    watch(d.id);
  } else {
    const r = await post(`/api/behaviors/runs/${current.runId}/step`);
    if (r) log(`run ${r.id} ${r.behavior}: next phase`, "ok");
  }
}

async function cancel() {
  if (current && current.runId !== null) await post(`/api/behaviors/runs/${current.runId}/cancel`);
  log("preview cancelled: nothing moved", "ok");
  close();
}

// while stepping: say whether the run waits for Step; close the preview when the run ends
function watch(id) {
  const timer = setInterval(async () => {
    if (!current || current.runId !== id) { clearInterval(timer); return; }
    const r = await api("GET", `/api/behaviors/runs/${id}`);
    if (!r) return;
    const btn = $("preview-step");
    if (btn) setText(btn, r.waiting ? `Step (next: ${r.result.phase || "?"})` : "Step");
    if (r.state !== "running") { clearInterval(timer); close(); }
  }, POLL_MS);
}
