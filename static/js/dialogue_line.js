// One line of the dialogue ([OP] II: the robot and the operator share perception and decisions): who said it
// (you, the robot, another client by the display name it chose), what, in words, at which simulated time, the raw
// JSON behind a click on it, and the buttons that answer a question of the robot. api.js's log() writes here.
import {$, el, fmt} from "./dom.js";

const MAX_LINES = 300;  // the oldest go beyond this
const SPEAKER = {cmd: "you"};  // the page's own commands are the operator's

// `actions`: [{label, title, act}] buttons; `act()` resolves truthy once done, and the line then says `done`
export function writeLine(text, {kind = "", who = null, time = null, details = null, actions = []} = {}) {
  const h = $("history");
  const speaker = who ?? SPEAKER[kind] ?? null;
  const head = [];
  if (time !== null && time !== undefined) head.push(el("span", {class: "t", text: `${fmt(time, 2)} s `}));
  if (speaker) head.push(el("span", {class: "who", text: `${speaker}: `}));
  head.push(el("span", {class: "words", text}));
  const li = el("li", {class: kind});
  if (speaker) li.dataset.who = speaker;
  if (details !== null && details !== undefined) {
    li.append(el("details", {}, el("summary", {title: "the details (raw JSON)"}, ...head),
                 el("pre", {class: "raw", text: JSON.stringify(details, null, 2)})));
  } else li.append(...head);
  if (actions.length) li.append(actionButtons(li, actions));
  h.append(li);
  while (h.children.length > MAX_LINES) h.firstChild.remove();
  h.scrollTop = h.scrollHeight;
  return li;
}

function actionButtons(li, actions) {
  const box = el("span", {class: "actions"});
  for (const a of actions) {
    box.append(el("button", {type: "button", text: a.label, title: a.title || "", onclick: async (e) => {
      e.currentTarget.disabled = true;
      const ok = await a.act();
      if (ok) answered(li, a.done || `${a.label}: done`);
      else e.currentTarget.disabled = false;
    }}));
  }
  return box;
}

// a question settled (by its button, or by what happened meanwhile): its buttons go, the answer is said
export function answered(li, text) {
  if (!li || li.classList.contains("answered")) return;
  li.classList.add("answered");
  const box = li.querySelector(".actions");
  if (box) box.remove();
  li.append(el("span", {class: "answer", text: ` - ${text}`}));
}
