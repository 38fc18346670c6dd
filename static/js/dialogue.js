// The dialogue ([OP] II and Fig. 5's Command Dialogue Box: the robot and the operator share perception and
// decisions): each run's outcome in words with its cause and the one action that resolves it, a latched stop
// asked as a question with the button that releases it, a recognition to confirm or correct, the other clients'
// commands by the display name they chose, and this page's display name setting. The lines: dialogue_line.js.
import {CLIENT_ID, latest, log, post, renew, sayRefusals, setClientId} from "./api.js";
import {myRuns, openFormOf, startBehavior} from "./behaviours.js";
import {answered} from "./dialogue_line.js";
import {$, el, fmt, xyz} from "./dom.js";
import {checkDisplayName} from "./estop.js";
import {forRefusal, forRun, releaseOf, stopIn} from "./remedies.js";
import {telemetryWs} from "./state.js";
import {opWsLatest} from "./sticks.js";

// the closed set of a run's causes (behaviors/causes.py), in the operator's words
const CAUSE_WORDS = {
  stop: "a latched stop", cancel: "cancelled", reset: "the simulation was reset", fall: "the robot fell",
  lock: "the operator lock", limit: "a limit (IK, joint limit, collision or reach)", timeout: "it overran its time",
  perception: "perception (not seen, slipped or nothing grasped)",
};
const scene = () => (latest.state && latest.state.scene) || "default";

// a remedy (remedies.js) as a button of the line; `run` for the ones that start or edit it again
function action(remedy, run = null) {
  const act = async () => {
    if (remedy.post) return !!(await post(remedy.post[0], remedy.post[1]));
    if (remedy.rerun) return !!(await startBehavior(run.behavior, run.params, `${run.behavior} ${JSON.stringify(run.params)}`));
    if (remedy.edit) return openFormOf(run.behavior);
    if (remedy.lock) { $("lock-btn").click(); return true; }
    return false;
  };
  return {label: remedy.label, title: remedy.title, done: remedy.done, act};
}
const actions = (remedy, run) => (remedy ? [action(remedy, run)] : []);

// ---- the runs: an outcome in words, a failure with its cause and what resolves it ------------------------------
const runStates = new Map();  // run id -> the state last seen
let runsSeen = false;  // the runs that had ended before this page opened are not told again
export function runsInWords(runs) {
  for (const r of runs) {
    const before = runStates.get(r.id);
    runStates.set(r.id, r.state);
    if (before === r.state || r.state === "running" || (before === undefined && !runsSeen)) continue;
    const took = r.ended_s !== null && r.ended_s !== undefined ? ` in ${fmt(r.ended_s - r.started_s, 1)} s` : "";
    const whose = myRuns.has(r.id) ? "" : ", another client's";
    const said = r.message.startsWith(`${r.behavior} `) ? r.message.slice(r.behavior.length + 1) : r.message;
    const text = `${r.behavior} ${r.state}${took}: ${said} (run ${r.id}${whose})`;
    if (r.state === "succeeded") {
      log(text, "ok", {who: "robot", details: r});
      if (r.result && r.result.recognition) askRecognitions();
      continue;
    }
    const cause = r.cause ? `cause: ${CAUSE_WORDS[r.cause] || r.cause}` : "no cause named";
    const remedy = forRun(r, scene());
    const li = log(`${text}; ${cause}`, remedy ? "bad ask" : "bad", {who: "robot", details: r, actions: actions(remedy, r)});
    const stop = r.cause === "stop" ? stopIn(r.message || "") : null;
    if (stop && stopLines[stop] !== null) stopFollowers[stop].push(li);  // settled with the stop's question
  }
  runsSeen = true;
}

// ---- a refused request: what refused it (409's reason, 423's holder) and what resolves it -------------------------
sayRefusals(({method, url, body, status, answer, text}) => {
  const reason = status === 423 ? "locked" : answer.reason;
  const words = reason ? `refused (${reason}): ${answer.detail || text}` : text;
  const remedy = forRefusal(status, reason, scene());
  const li = log(words, remedy ? "bad ask" : "bad", {who: "robot", actions: actions(remedy),
                 details: {request: `${method} ${url}`, body: body ?? null, status, answer}});
  const stop = {hard_stop: "hard", motion_stop: "motion", walking_stop: "walking"}[reason];
  if (stop && stopLines[stop] !== null) stopFollowers[stop].push(li);  // settled with the stop's question
});

// ---- latched stops as questions: what raised it, the value and when, and the button that releases it -----------
const stopLines = {hard: null, motion: null, walking: null, fall: null};
const MOTION_BY = {operator: "the operator (Stop motion)",
                   emergency_step: "the AutoBalancer's capture-point emergency step"};
function motionWords(em, s) {
  const by = em.motion_stop_reason === "capture_point"
    ? `the capture-point flag (|CP error| ${fmt(1000 * em.motion_stop_cp_error_m, 1)} mm when it rose, threshold ` +
      `${fmt(1000 * ((s.capture_point || {}).cp_threshold_m), 1)} mm)`
    : MOTION_BY[em.motion_stop_reason] || em.motion_stop_reason || "?";
  return `motion stop latched by ${by} at ${fmt(em.motion_stop_time, 3)} s: the planned motion is held, balance ` +
    "keeps working. Release it?";
}
const stopFollowers = {hard: [], motion: [], walking: [], fall: []};  // the runs' failures a stop caused
function ask(stop, on, words, details, remedy, gone) {
  const li = stopLines[stop];
  if (on && li === null) stopLines[stop] = log(words(), "bad ask", {who: "robot", details, actions: actions(remedy)});
  else if (!on && li !== null) {
    for (const f of [li, ...stopFollowers[stop]]) answered(f, gone);
    stopLines[stop] = null;
    stopFollowers[stop] = [];
  }
}
export function stopsInWords(s) {
  const em = s.emergency || {};
  const t = `at ${fmt(s.time, 2)} s`;
  const pick = (...keys) => Object.fromEntries(keys.map((k) => [k, em[k]]));
  ask("hard", !!em.hard_stop, () => `hard e-stop engaged (${em.hard_stop_reason || "?"}${em.fault ? `, fault: ${em.fault}` : ""}): ` +
      "the joint command is frozen. Release it?", pick("hard_stop", "hard_stop_reason", "fault"), releaseOf("hard"),
      `released ${t}`);
  ask("motion", !!em.motion_stop, () => motionWords(em, s),
      pick("motion_stop", "motion_stop_reason", "motion_stop_time", "motion_stop_cp_error_m", "flag"),
      releaseOf("motion"), `released ${t}`);
  ask("walking", !!em.walking_stop, () => "emergency walking stop: stopping in place; it ends by itself once the " +
      "feet stand side by side", pick("walking_stop", "walk_cut"), releaseOf("walking"), `ended ${t}`);
  ask("fall", !!s.fallen, () => `the robot has fallen (${em.fall || "?"}): reset the simulation?`, pick("fall"),
      forRun({cause: "fall"}, scene()),
      `standing again ${t}`);
}

// ---- recognitions: the robot asks whether the object is where it says; confirm or correct --------------------
const asked = new Map();  // object -> the recognition time asked about
const recognitionLines = new Map();  // object -> its question's line, until answered (here, the pop-up, a client)
async function askRecognitions() {
  const r = await fetch("/api/recognitions").catch(() => null);
  const d = r && r.ok ? await r.json() : {recognitions: {}};
  for (const [name, rec] of Object.entries(d.recognitions || {})) {
    if (asked.get(name) === rec.time_s || rec.status) continue;
    asked.set(name, rec.time_s);
    const sigma = rec.sigma_m ? `, sigma ${fmt(1000 * Math.hypot(rec.sigma_m[0], rec.sigma_m[1]), 1)} mm` : "";
    const li = log(`I see the ${name} at ${xyz(rec.position_m)} m${sigma}: is it there?`, "ask",
                   {who: "robot", details: rec, actions: [
                     {label: "Confirm", title: `POST /api/recognitions/${name}/confirm`, done: "confirmed",
                      act: async () => !!(await post(`/api/recognitions/${name}/confirm`, {}))},
                     {label: "Correct", title: "Give where it is (world x y z [m])", act: () => correctForm(li, name, rec)}]});
    recognitionLines.set(name, li);
  }
}
function correctForm(li, name, rec) {
  if (li.querySelector("form.correct")) return false;
  const inputs = ["x", "y", "z"].map((axis, i) => el("input", {type: "number", step: "any", min: -20, max: 20,
    value: rec.position_m[i], "aria-label": `${name} ${axis} [m]`, required: true}));
  const form = el("form", {class: "correct", "aria-label": `where the ${name} is`}, ...inputs,
                  el("button", {type: "submit", text: "Send"}));
  form.addEventListener("submit", async (e) => {
    e.preventDefault();
    const d = await post(`/api/recognitions/${name}/correct`, {position_m: inputs.map((x) => Number(x.value))});
    if (d) { form.remove(); answered(li, d.message); }
  });
  li.append(form);
  inputs[0].focus();
  return false;  // answered once sent
}

// ---- the other clients' commands (the console's journal), by the display name they chose ----------------------
let lastSeq = null;
export function commandsInWords(commands) {
  const newest = commands.length ? commands[commands.length - 1].seq : 0;
  if (lastSeq === null || newest < lastSeq) { lastSeq = newest; return; }  // (re)started: not replayed
  for (const c of commands) {
    if (c.seq <= lastSeq) continue;
    const rec = c.status < 300 && /^POST \/api\/recognitions\/([^/]+)\/(confirm|correct)$/.exec(c.request);
    if (rec && recognitionLines.has(rec[1])) {  // the question answered, whoever answered it
      answered(recognitionLines.get(rec[1]), `${c.answer} (${c.client === CLIENT_ID ? "you" : c.client})`);
      recognitionLines.delete(rec[1]);
    }
    if (c.client === CLIENT_ID) continue;
    const times = c.count > 1 ? ` (x${c.count})` : "";
    const said = c.status < 300 ? (c.answer || `${c.request}: ok`) : `${c.request} refused (${c.status}): ${c.answer}`;
    log(said + times, c.status < 300 ? "other" : "bad", {who: c.client, details: c});
  }
  lastSeq = newest;
}

// ---- this page's display name: the others see it (its requests, its streams, the lock) ------------------------
const nameForm = $("name-form");
$("display-name").value = CLIENT_ID;
nameForm.addEventListener("submit", (e) => {
  e.preventDefault();
  const name = $("display-name").value.trim();
  const bad = checkDisplayName(name) || ($("lock-state").classList.contains("mine")
    ? `display name: release control first (the lock is held as '${CLIENT_ID}')` : "");
  $("name-error").textContent = bad || "";
  $("display-name").setAttribute("aria-invalid", bad ? "true" : "false");
  if (bad || name === CLIENT_ID) return;
  const before = CLIENT_ID;
  setClientId(name);
  for (const ws of [opWsLatest, telemetryWs]) renew(ws);  // their ?client= is the new name
  log(`you are now "${name}" to the other clients (were "${before}")`, "ok");
});
