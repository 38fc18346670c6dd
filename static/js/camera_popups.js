// The recognitions over the camera view: one box and one pop-up per object, kept inside the frame (beside the box
// where there is room, never over another pop-up when it can be helped), updated as the object moves, removed when
// the robot holds it; a landing verdict ("in the box" / "out of the box") shown without Confirm / Correct.
import {log, post} from "./api.js";
import {$, el, fmt, setClass, xyz} from "./dom.js";

const GAP_PX = 4;  // between a box and its pop-up, and from the frame's edge
// Statuses of a verdict the robot made (throw_can's look at the box): shown, not to be confirmed or corrected.
const VERDICTS = new Set(["in the box", "out of the box"]);
const HELD = "held";  // the robot holds the object: nothing in the view to point at, no pop-up

const popups = new Map();  // object name -> {box, pop, key, editing}
let lastMeta = null;

// A pop-up of size w x h [px] for an object whose box is `box` (null: out of view), in a W x H frame, avoiding the
// rectangles already `placed` and its own box: the first of right, left, below, above that fits whole and overlaps
// nothing, else the one that overlaps least, pushed inside the frame. Returns {left, top}.
export function placePopup(box, w, h, W, H, placed) {
  const clamp = (v, lo, hi) => Math.max(lo, Math.min(v, Math.max(lo, hi)));
  const inside = (x, y) => ({left: clamp(x, 0, W - w), top: clamp(y, 0, H - h)});
  const avoid = box ? [...placed, {left: box[0], top: box[1], w: box[2] - box[0], h: box[3] - box[1]}] : placed;
  const overlap = (a) => avoid.reduce((s, r) => s + Math.max(0, Math.min(a.left + w, r.left + r.w) -
    Math.max(a.left, r.left)) * Math.max(0, Math.min(a.top + h, r.top + r.h) - Math.max(a.top, r.top)), 0);
  const candidates = box ? [
    [box[2] + GAP_PX, box[1]], [box[0] - GAP_PX - w, box[1]], [box[0], box[3] + GAP_PX], [box[0], box[1] - GAP_PX - h],
  ] : [[GAP_PX, GAP_PX], [GAP_PX, H - h - GAP_PX], [W - w - GAP_PX, GAP_PX], [W - w - GAP_PX, H - h - GAP_PX]];
  let best = null;
  for (const [x, y] of candidates) {
    const at = inside(x, y);
    const fits = at.left === x && at.top === y;
    const cost = overlap(at) + (fits ? 0 : 1e6);
    if (cost === 0) return at;
    if (!best || cost < best.cost) best = {...at, cost};
  }
  if (overlap(best) > 0) {  // slide down (then up) past the pop-ups in the way, still inside the frame
    for (let top = 0; top + h <= H; top += 8) {
      if (!overlap({left: best.left, top})) return {left: best.left, top};
    }
  }
  return {left: best.left, top: best.top};
}

export function drawRecognitions(meta) {
  lastMeta = meta;
  const frame = $("camera-frame");
  const W = frame.clientWidth, H = frame.clientHeight;
  const sx = W / (meta.width || 320), sy = H / (meta.height || 240);
  const seen = new Set();
  const placed = [];
  for (const r of meta.recognitions || []) {
    const status = r.status || "estimated";
    if (status === HELD) continue;
    seen.add(r.name);
    let p = popups.get(r.name);
    if (!p) {
      p = {box: el("div", {class: "rec-box"}), pop: el("div", {class: "rec-pop", role: "dialog",
                                                               "aria-label": `recognition of ${r.name}`}),
           key: null, editing: false};
      $("camera-popups").append(p.box, p.pop);
      popups.set(r.name, p);
    }
    setClass(p.box, `rec-box ${VERDICTS.has(status) ? "verdict" : status}`);
    setClass(p.pop, `rec-pop ${VERDICTS.has(status) ? "verdict" : status}`);
    const key = JSON.stringify([r.position_m, status, r.time_s, Boolean(r.box_px)]);
    if (key !== p.key && !p.editing) {
      if (p.key === null || JSON.parse(p.key)[2] !== r.time_s) {  // a new recognition: into the history too
        log(`recognition: ${r.name} at ${xyz(r.position_m)} m (${status})` +
            (VERDICTS.has(status) ? "" : "; confirm or correct it over the camera view"), "other");
      }
      p.key = key;
      renderPopup(p, r, status);
    }
    p.pop.style.maxWidth = `${W - 2 * GAP_PX}px`;
    p.pop.style.maxHeight = `${H - 2 * GAP_PX}px`;
    let box = null;
    if (r.box_px) {
      const [u0, v0, u1, v1] = r.box_px;
      box = [u0 * sx, v0 * sy, u1 * sx, v1 * sy];
      Object.assign(p.box.style, {left: `${box[0]}px`, top: `${box[1]}px`, width: `${box[2] - box[0]}px`,
                                  height: `${box[3] - box[1]}px`, display: "block"});
    } else {
      p.box.style.display = "none";
    }
    const w = p.pop.offsetWidth, h = p.pop.offsetHeight;
    const at = placePopup(box, w, h, W, H, placed);
    placed.push({...at, w, h});
    Object.assign(p.pop.style, {left: `${at.left}px`, top: `${at.top}px`});
  }
  for (const [name, p] of popups) {
    if (!seen.has(name)) { p.box.remove(); p.pop.remove(); popups.delete(name); }
  }
}

// The camera box resized (its corner): the boxes and pop-ups laid out again for the new size.
export function watchFrameSize() {
  if (typeof ResizeObserver === "undefined") return;
  new ResizeObserver(() => { if (lastMeta) drawRecognitions(lastMeta); }).observe($("camera-frame"));
}

function renderPopup(p, r, status) {
  const sigma = r.sigma_m ? Math.hypot(r.sigma_m[0], r.sigma_m[1]) * 1000 : null;
  if (VERDICTS.has(status)) {
    p.pop.replaceChildren(el("div", {class: "verdict-text", text: `${r.name}: ${status}`}),
                          el("div", {text: r.verdict_detail || `at ${xyz(r.position_m)} m`}));
    return;
  }
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
