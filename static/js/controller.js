// Controller management: start/stop pairs and parameter panels generated from the OpenAPI document, the
// simulation reset, parameters dumped to and loaded from JSON, and the joint form (the sequence player).
import {api, log, post, postLogged, say} from "./api.js";
import {$, el} from "./dom.js";

export async function buildController(openapi, cfg) {
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
                      onclick: () => postLogged(`/api/${seg}/start`)}),
        el("button", {type: "button", text: "stop", "aria-label": `stop ${label}`,
                      onclick: () => postLogged(`/api/${seg}/stop`)})));
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
    const fields = leaves(ownerSchema);
    for (const [name, fs] of fields) {
      const id = `pp-${owner}-${name}`;
      const value = at(current[owner], name);
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
      for (const [name, fs] of fields) {
        const input = $(`pp-${owner}-${name}`);
        let v;
        if (fs.type === "boolean") v = input.checked;
        else if (fs.enum) v = fs.enum.find((c) => String(c) === input.value);
        else if (fs.type === "number" || fs.type === "integer") { if (input.value === "") continue; v = Number(input.value); }
        else { try { v = JSON.parse(input.value); } catch (err) { v = input.value; } }
        if (JSON.stringify(v) !== JSON.stringify(at(current[owner], name))) changes[name] = v;
      }
      if (!Object.keys(changes).length) { say(`${owner}: nothing changed`); return; }
      // dotted names ("emergency_step.step_time_s") are a nested parameter's fields: the API takes them as they are
      api("PUT", "/api/params", {[owner]: changes}).then((d) => {
        if (d) { current[owner] = d[owner]; log(`${owner} parameters set: ${JSON.stringify(changes)}`, "ok"); }
      });
    });
    panels.append(el("details", {}, el("summary", {text: `${owner} parameters`}), grid));
  }
}

// the fields of a params schema as [dotted name, field schema], a nested object's fields one row each
function leaves(schema, prefix = "") {
  return Object.entries(schema.properties || {}).flatMap(([name, fs]) =>
    fs.type === "object" && fs.properties ? leaves(fs, `${prefix}${name}.`) : [[prefix + name, fs]]);
}
// the value at a dotted name in the current parameters
function at(values, name) {
  return name.split(".").reduce((v, key) => (v == null ? undefined : v[key]), values);
}

$("reset-form").addEventListener("submit", (e) => {
  e.preventDefault();
  log(`reset ${$("scene").value}`, "cmd");
  postLogged("/api/sim/reset", {scene: $("scene").value});
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
// the joints and their limits from /api/config; RARM_JOINT0 chosen first
export function setJoints(cfg) {
  limits = cfg.joint_limits_deg || {};
  for (const name of cfg.joints || []) $("joint").append(el("option", {value: name, text: name}));
  if (cfg.joints && cfg.joints.includes("RARM_JOINT0")) { $("joint").value = "RARM_JOINT0"; $("joint").dispatchEvent(new Event("change")); }
}
$("joint").addEventListener("change", () => {
  const lim = limits[$("joint").value];
  if (lim) { $("angle").min = lim[0]; $("angle").max = lim[1]; $("angle").title = `range ${lim[0]} .. ${lim[1]} deg`; }
});
$("joint-form").addEventListener("submit", (e) => {
  e.preventDefault();
  const angles = {[$("joint").value]: Number($("angle").value)};
  post("/api/sequence/joint-angles", {angles_deg: angles, time: Number($("duration").value)});
});
