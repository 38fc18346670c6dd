// The one action that resolves what is in the way: for each cause of a failed run (behaviors/causes.py's closed
// set, the run's `cause`) and each reason of a refusal (409's `reason`, 423 the lock), what the dialogue offers.
// Their labels differ from the safety bar's and the lock's buttons: each button of the page has a name of its own.
// Descriptors only: {label, title, post: [path, body]} a request, {label, title, rerun: true} the run again,
// {label, title, edit: true} its form, {label, title, lock: true} take control. null: nothing the page can do.

const RELEASE = {
  motion: {label: "Release the motion stop", done: "released", title: "Blend back to the planned motion (POST /api/motion/release)",
           post: ["/api/motion/release"]},
  walking: {label: "Release the walking stop", done: "goStop sent", title: "Send goStop (POST /api/walk/stop); it also ends by itself once standing",
            post: ["/api/walk/stop"]},
  hard: {label: "Release the e-stop", done: "released", title: "Release the hard e-stop (POST /api/estop/release)", post: ["/api/estop/release"]},
};
const RESET = (scene) => ({label: "Reset the simulation", done: "reset", title: `POST /api/sim/reset to the ${scene} scene`,
                           post: ["/api/sim/reset", {scene}]});
const RERUN = {label: "Run again", title: "Start the same behaviour with the same parameters", rerun: true};
const TAKE = {label: "Take the operator lock", title: "Take the operator lock (when its holder has released it)", lock: true};

// which stop a message names (a stop's words, app/service/stops.py)
export function stopIn(message) {
  if (/motion stop/i.test(message)) return "motion";
  if (/walking stop/i.test(message)) return "walking";
  if (/e-stop|hard stop/i.test(message)) return "hard";
  return null;
}
export const releaseOf = (stop) => RELEASE[stop] || null;

export function forRun(run, scene) {
  switch (run.cause) {
    case "stop": return releaseOf(stopIn(run.message || ""));
    case "fall": return RESET(scene);
    case "lock": return TAKE;
    case "limit": return {label: `Edit ${run.behavior}`, title: "Open its form: a target it can reach", edit: true};
    default: return RERUN;  // cancel, reset, timeout, perception, none named: the same again
  }
}

export function forRefusal(status, reason, scene) {
  if (status === 423) return TAKE;
  switch (reason) {
    case "hard_stop": return RELEASE.hard;
    case "motion_stop": return RELEASE.motion;
    case "walking_stop": return RELEASE.walking;
    case "fallen": return RESET(scene);
    default: return null;  // collision, reach, state, point_taken, superseded: the operator decides
  }
}
