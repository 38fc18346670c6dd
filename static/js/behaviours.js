// Behaviours: a button and a generated form per registered behaviour (GET /api/behaviors), the runs with their
// progress and cancel (their outcomes in words: js/dialogue.js), and the command box (`name v1 v2 ...` or `name k=v`, with the built-in commands).
import {api, headers, log, post, postLogged, say} from "./api.js";
import {$, el, fmt, xyz} from "./dom.js";
import {estop} from "./estop.js";
import {MOVERS, confirmSwitch, showPreview, startOrPreview} from "./preview.js";

let behaviors = [];
export const myRuns = new Set();  // the runs this page started (its dialogue says so)

export async function loadBehaviors() {
  behaviors = await api("GET", "/api/behaviors") || [];
  $("behaviors").replaceChildren(...behaviors.map((b) => el("button", {type: "button", text: b.name, title: b.summary,
                                                                        "data-behavior": b.name, onclick: () => openForm(b)})),
                                 confirmSwitch());
}

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

// the form of the behaviour named `name`, opened (the dialogue's "Edit" of a run a limit stopped): found or not
export function openFormOf(name) {
  const b = behaviors.find((x) => x.name === name);
  if (b) openForm(b);
  return !!b;
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
              MOVERS.has(b.name) ? el("button", {type: "button", text: "Preview", onclick: () => {
                const body = formBody(b);
                if (body) showPreview(b.name, body, `${b.name} ${JSON.stringify(body)}`, startBehavior);
              }}) : "",
              el("button", {type: "button", text: "Close", onclick: () => { f.hidden = true; }})));
  f.dataset.behavior = b.name;
  f.hidden = false;
}

function formBody(b) {
  const body = {};
  for (const p of b.params) {
    const input = $(`bp-${b.name}-${p.name}`);
    if (p.type === "boolean") body[p.name] = input.checked;
    else if (p.type === "number") body[p.name] = Number(input.value);
    else if (p.type === "integer") body[p.name] = Math.round(Number(input.value));
    else if (p.type === "array") {
      try { body[p.name] = JSON.parse(input.value || "[]"); } catch (err) { say(`${p.name}: not JSON (${err.message})`, true); return null; }
    } else body[p.name] = input.value;
  }
  return body;
}

$("behavior-form").addEventListener("submit", (e) => {
  e.preventDefault();
  const b = behaviors.find((x) => x.name === $("behavior-form").dataset.behavior);
  const body = formBody(b);
  if (body) startOrPreview(b.name, body, `${b.name} ${JSON.stringify(body)}`, startBehavior);
});

export async function startBehavior(name, body, shown, mode = "run") {
  log(`${shown}`, "cmd");
  const d = await post(`/api/behaviors/${name}${mode === "step" ? "?mode=step" : ""}`, body);
  if (d) { myRuns.add(d.id); log(d.message, "ok", {who: "robot", details: d}); }
  return d;
}

export function updateRuns(runs) {
  const box = $("runs");
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
  release: () => postLogged("/api/estop/release"),
  stop: () => postLogged("/api/motion/stop"),
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
    if (BUILTINS[word]) { log(`${text}`, "cmd"); await BUILTINS[word](args); }
    else {
      const {name, body, places} = await parseCommand(text);
      if (places.length) { log(`${text}`, "cmd"); for (const p of places) log(p, "ok"); }
      await startOrPreview(name, body, places.length ? `${name} ${JSON.stringify(body)}` : text, startBehavior);
    }
    $("command").value = "";
  } catch (err) {
    log(`${text}`, "cmd");
    log(err.message, "bad");
    say(err.message, true);
  }
});
