// The operator lock: who holds it, shown to all; a watcher's controls greyed out (E-STOP never); the button that
// takes and gives it back.
import {CLIENT_ID, api, lockToken, log, post, renew, setLockToken} from "./api.js";
import {$, setClass, setText} from "./dom.js";
import {telemetryWs} from "./state.js";
import {opWsLatest} from "./sticks.js";

let lockHolder = null;
let taking = false;  // this page's take in flight: a state naming it before the answer came is not another's
export function updateLock(lock) {
  const holder = lock ? lock.holder : null;
  const mine = holder === CLIENT_ID && (lockToken !== null || taking);
  const watching = holder !== null && !mine;
  const st = $("lock-state");
  setText(st, holder === null ? "control: free (anyone)" : mine ? "control: YOU" : `control: ${holder} (watching)`);
  setClass(st, holder === null ? "" : mine ? "mine" : "other");
  setText($("lock-btn"), mine ? "Release control" : "Take control");
  const title = mine ? "Give the operator lock back: any client may control again"
    : watching ? `${holder} holds control; taking it is refused until they release it or leave`
    : "Take the operator lock: the others can only watch (and press E-STOP)";
  if ($("lock-btn").title !== title) $("lock-btn").title = title;
  if (watching !== document.body.classList.contains("watching")) {
    document.body.classList.toggle("watching", watching);
    for (const sec of document.querySelectorAll("#controls > section")) sec.inert = watching;
    for (const b of document.querySelectorAll(".stop .rel, #walk-estop, #st-stop")) b.disabled = watching;
    $("camera-popups").inert = watching;
    if (watching) log(`${holder} took control: this page watches (E-STOP stays available)`, "other");
    else if (lockHolder !== null && lockHolder !== CLIENT_ID) log("control is free again", "other");
  }
  lockHolder = holder;
}
$("lock-btn").addEventListener("click", async () => {
  if (lockHolder === CLIENT_ID && lockToken !== null) {
    const d = await api("DELETE", "/api/operator/lock");
    if (d) { setLockToken(null); log("control released", "ok"); }
  } else {
    taking = true;
    const d = await post("/api/operator/lock", {client: CLIENT_ID}).finally(() => { taking = false; });
    if (d && d.token) {
      setLockToken(d.token);
      // the stick stream and the telemetry reconnect at once with the lease token (the holder's stream is the
      // one that may steer; an open one keeps the lock)
      for (const ws of [opWsLatest, telemetryWs]) renew(ws);
      updateLock(d);
      log("you have control", "ok");
    }
  }
});
