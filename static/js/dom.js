// Small DOM and number-format helpers every part of the operator page uses.

export const $ = (id) => document.getElementById(id);
export const fmt = (v, d = 3) => (v === null || v === undefined || Number.isNaN(Number(v))) ? "-" : Number(v).toFixed(d);
export const xyz = (p) => `(${p.map((v) => fmt(v, 3)).join(", ")})`;
export const el = (tag, attrs = {}, ...children) => {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "class") e.className = v;
    else if (k === "text") e.textContent = v;
    else if (k.startsWith("on")) e.addEventListener(k.slice(2), v);
    else if (v !== undefined && v !== null && v !== false) e.setAttribute(k, v === true ? "" : v);
  }
  for (const c of children) e.append(c);
  return e;
};
// Writes only what changed. The browser lays the page out again after any write, an unchanged one too, and this
// page's thread does that work in the way of its input: the E-STOP's pointer-down waits behind it.
export function setText(node, text) { if (node.textContent !== text) node.textContent = text; }
export function setClass(node, cls) { if (node.className !== cls) node.className = cls; }
