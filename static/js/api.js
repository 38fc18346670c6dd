// The page's requests to the API (with the token, the client id and the lock's lease), its WebSocket addresses,
// and the history and message line that say what came back.
import {$} from "./dom.js";
import {writeLine} from "./dialogue_line.js";
import {CLIENT_ID, TOKEN, headers, lockToken, logTo} from "./estop.js";

// the page's identity is defined beside the E-STOP, which needs it and nothing else
export {CLIENT_ID, headers, lockToken, setClientId, setLockToken} from "./estop.js";

// the newest state received (state.js keeps it): its time stamps the history
export const latest = {state: null};

export function wsUrl(path) {
  const url = new URL(path, location.href);
  url.protocol = location.protocol === "https:" ? "wss:" : "ws:";
  if (TOKEN) url.searchParams.set("token", TOKEN);
  url.searchParams.set("client", CLIENT_ID);
  if (lockToken) url.searchParams.set("lock_token", lockToken);  // the holder's stream; an open one keeps the lock
  return url.href;
}
// closed to be opened again at once (with the lease token just taken)
export function renew(ws) {
  if (ws && ws.readyState <= WebSocket.OPEN) { ws.renewed = true; ws.close(); }
}

// ---- the dialogue: commands, results, faults, what other clients did (js/dialogue_line.js draws a line) ---------
// `extra`: who said it, the details behind a click, the buttons that answer it (dialogue_line.js's writeLine)
export function log(text, kind = "", extra = {}) {
  return writeLine(text, {kind, time: latest.state ? latest.state.time : null, ...extra});
}
// what the dialogue says of a refused request instead of the plain line (js/dialogue.js installs it)
let refusalLine = null;
export function sayRefusals(fn) { refusalLine = fn; }
logTo(log);
export function say(text, bad = false) {
  const m = $("message");
  m.textContent = text;
  m.className = bad ? "alarm" : "";
}

export async function api(method, url, body) {
  try {
    const r = await fetch(url, {method, headers: headers(method !== "GET"),
                                body: body === undefined ? undefined : JSON.stringify(body)});
    const data = await r.json().catch(() => ({}));
    if (!r.ok) {
      const why = r.status === 423 ? `another operator holds control (${data.holder || data.detail || "?"})`
        : (data.detail || r.statusText);
      const text = `${method} ${url}: ${r.status} ${typeof why === "string" ? why : JSON.stringify(why)}`;
      say(text, true);
      if (refusalLine) refusalLine({method, url, body, status: r.status, answer: data, text});
      else log(text, "bad");
      return null;
    }
    if (data.message) say(data.message);
    return data;
  } catch (e) {
    say(`${method} ${url}: ${e}`, true);
    log(`${method} ${url}: ${e}`, "bad");
    return null;
  }
}
export const post = (url, body) => api("POST", url, body);
// a POST whose answer's message goes into the history
export const postLogged = (url, body) => post(url, body).then((d) => d && log(d.message, "ok"));
