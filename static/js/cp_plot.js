// The capture-point error panel: x, y, |e| [mm] with the flag's threshold, the support edge (how far the
// reference CP is inside the support polygon: the error at which the actual one leaves it) and the flag band
// (shaded while the Stabilizer's CP flag is up), over the last 10 s of the run's simulated time.
import {el, fmt, setClass, setText} from "./dom.js";

const WINDOW_S = 10;
const RANGE_MM = 100;  // the fixed y range +-[mm] (as the 3D view's plot): the default 40 mm threshold stays readable
const TICK_S = 2;  // [s] between the time axis' labels
const AXIS_PX = 14;  // the time axis' strip at the bottom
const COLORS = {x: "#e6194b", y: "#3c78d8", norm: "#1b1f24", thr: "#888", edge: "#b8860b", flag: "rgba(200,16,46,0.18)"};

// The canvas' pixels follow its CSS box (the panels are resizable): true when they changed. Its size is read only
// after the ResizeObserver said it changed (a read each frame would make the browser lay the page out for it).
const observed = new WeakSet(), resized = new WeakSet();
const observer = new ResizeObserver((entries) => { for (const e of entries) resized.add(e.target); });
function fitCanvas(c) {
  if (!observed.has(c)) { observed.add(c); observer.observe(c); resized.add(c); }
  if (!resized.has(c)) return false;
  resized.delete(c);
  const w = Math.max(1, Math.round(c.clientWidth)), h = Math.max(1, Math.round(c.clientHeight));
  if (c.width === w && c.height === h) return false;
  c.width = w; c.height = h;
  return true;
}

// A plot's redraw prelude, shared by every plot of the page: refit the canvas, skip when nothing changed, count the
// redraw, clear. The 2D context to draw on, or null when there is nothing to redraw.
export function beginDraw(plot) {
  if (fitCanvas(plot.canvas)) plot.dirty = true;
  if (!plot.dirty) return null;
  plot.dirty = false;
  plot.draws += 1;
  const c = plot.canvas, g = c.getContext("2d");
  g.clearRect(0, 0, c.width, c.height);
  return g;
}

export class CpPlot {
  constructor(canvas, legend) {
    this.canvas = canvas; this.legend = legend;
    this.draws = 0; this.samples = 0;  // (the browser tests and the page-rates benchmark read them)
    this.axis = {t0: 0, t1: 0, ticks: []};  // the time axis as last drawn [s]
    this.clear();
  }
  clear() {
    this.t = []; this.v = [];  // v[k]: [x, y, |e|, threshold, support edge (null: unknown), flag 0/1] [mm]
    this.dirty = true;
  }
  // One state's capture point and flag; a time that went back is a reset (the history starts again).
  push(t, cp, flag) {
    if (!cp || !cp.error || !Number.isFinite(t)) return;
    if (this.t.length && t < this.t[this.t.length - 1]) this.clear();
    if (this.t.length && t === this.t[this.t.length - 1]) return;
    const edge = cp.support_edge_m == null ? null : 1000 * cp.support_edge_m;
    this.t.push(t);
    this.v.push([1000 * cp.error[0], 1000 * cp.error[1], 1000 * cp.error_norm, 1000 * cp.cp_threshold_m, edge,
                 flag ? 1 : 0]);
    this.samples += 1;
    while (this.t.length && this.t[0] < t - WINDOW_S) { this.t.shift(); this.v.shift(); }
    this.dirty = true;
  }
  draw() {
    const g = beginDraw(this);
    if (!g) return;
    const c = this.canvas, W = c.width, H = c.height, pad = 4, plotH = H - AXIS_PX;
    if (!this.t.length) { this.axis = {t0: 0, t1: 0, ticks: []}; return; }
    let range = RANGE_MM;  // wider when the error leaves it (a push): nothing drawn off the canvas
    for (const r of this.v) range = Math.max(range, 1.1 * Math.abs(r[0]), 1.1 * Math.abs(r[1]), 1.1 * r[2]);
    const t1 = this.t[this.t.length - 1], t0 = t1 - WINDOW_S;
    const X = (t) => pad + (W - 2 * pad) * (t - t0) / WINDOW_S;
    const Y = (mm) => pad + (plotH - 2 * pad) * (range - mm) / (2 * range);
    // the flag band
    g.fillStyle = COLORS.flag;
    for (let k = 0; k < this.t.length; k++) {
      if (!this.v[k][5]) continue;
      const next = k + 1 < this.t.length ? this.t[k + 1] : t1;
      g.fillRect(X(this.t[k]), 0, Math.max(1, X(next) - X(this.t[k])), plotH);
    }
    // the zero line and the time axis (simulated time: never below 0, so a new run shows only its own times)
    g.strokeStyle = "#d8dce2"; g.lineWidth = 1;
    g.beginPath(); g.moveTo(pad, Y(0)); g.lineTo(W - pad, Y(0)); g.moveTo(pad, plotH); g.lineTo(W - pad, plotH); g.stroke();
    g.fillStyle = "#666"; g.font = "10px sans-serif"; g.textAlign = "center";
    const ticks = [];
    for (let s = Math.ceil(Math.max(t0, 0) / TICK_S) * TICK_S; s <= t1; s += TICK_S) {
      ticks.push(s);
      g.beginPath(); g.moveTo(X(s), plotH); g.lineTo(X(s), plotH + 3); g.stroke();
      g.fillText(`${s} s`, Math.min(Math.max(X(s), 14), W - 14), H - 2);
    }
    this.axis = {t0: Math.max(t0, this.t[0]), t1, ticks};
    g.textAlign = "left";
    g.fillText(`+${range.toFixed(0)} mm`, pad + 2, 11);
    g.fillText(`-${range.toFixed(0)} mm`, pad + 2, plotH - 4);
    // threshold (dashed), support edge (dotted), then the error
    const line = (i, sign, color, dash, width) => {
      g.strokeStyle = color; g.lineWidth = width; g.setLineDash(dash); g.beginPath();
      let started = false;
      this.t.forEach((t, k) => {
        const mm = this.v[k][i];
        if (mm == null || !Number.isFinite(mm)) { started = false; return; }
        const y = Y(Math.max(-range, Math.min(range, sign * mm)));
        if (started) g.lineTo(X(t), y); else { g.moveTo(X(t), y); started = true; }
      });
      g.stroke();
    };
    for (const sign of [1, -1]) { line(3, sign, COLORS.thr, [6, 4], 1); line(4, sign, COLORS.edge, [2, 3], 1); }
    g.setLineDash([]);
    line(0, 1, COLORS.x, [], 1.5); line(1, 1, COLORS.y, [], 1.5); line(2, 1, COLORS.norm, [], 1);
    this.writeLegend(t1, this.v[this.v.length - 1]);
  }
  writeLegend(t, [x, y, norm, thr, edge, flag]) {
    const lg = this.legend;
    if (lg.children.length !== 6) {
      const span = (color) => el("span", {style: `color:${color}; margin-right: 0.6em`});
      lg.replaceChildren(span(COLORS.x), span(COLORS.y), span(COLORS.norm), span(COLORS.edge), el("span"), el("span"));
    }
    setText(lg.children[0], `CP error x ${fmt(x, 1)}`);
    setText(lg.children[1], `y ${fmt(y, 1)}`);
    setText(lg.children[2], `|e| ${fmt(norm, 1)} / ${fmt(thr, 1)} mm`);
    setText(lg.children[3], `edge ${edge == null ? "-" : fmt(edge, 1)} mm`);
    setText(lg.children[4], flag ? "flag RAISED " : "flag off ");
    setClass(lg.children[4], flag ? "alarm" : "");
    setText(lg.children[5], `t ${fmt(t, 2)} s`);
  }
}
