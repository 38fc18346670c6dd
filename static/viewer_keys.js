// Added by the console to viser's client at /viewer/: the keys pressed inside the 3D view reach the operator
// page (Esc and Space engage the e-stop; the teleoperation keys drive the selected point), unless a text field
// of the viewer has the focus. Only the key's name crosses, by postMessage to the page that embeds the view.
"use strict";
(() => {
  if (window.parent === window) return;
  const TELEOP = /^(Key[WASDQEZC]|Arrow(Up|Down|Left|Right)|Digit[1-9])$/;
  function typing(t) {
    if (!t || !t.tagName) return false;
    const tag = t.tagName.toUpperCase();
    if (tag === "TEXTAREA" || t.isContentEditable) return true;
    return tag === "INPUT" && !["button", "checkbox", "radio", "range", "submit", "reset", "file", "color"]
      .includes((t.type || "text").toLowerCase());
  }
  function forward(e, down) {
    const stop = e.key === "Escape" || e.code === "Space";
    if ((!stop && !TELEOP.test(e.code)) || typing(e.target) || e.ctrlKey || e.metaKey || e.altKey) return;
    if (stop) { e.preventDefault(); e.stopPropagation(); }
    window.parent.postMessage({type: "hrp2-key", key: e.key, code: e.code, down, repeat: e.repeat}, "*");
  }
  window.addEventListener("keydown", (e) => forward(e, true), true);
  window.addEventListener("keyup", (e) => forward(e, false), true);
})();
