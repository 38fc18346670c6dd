// Plots from the telemetry: ZMP and COG x / y, the feet's vertical forces and the capture-point error (>= 20 Hz,
// last 10 s), redrawn once per animation frame when a sample came.
import {beginDraw, CpPlot} from "./cp_plot.js";
import {$, el, fmt, setText} from "./dom.js";

const PLOT_WINDOW_S = 10;
class TimePlot {
  constructor(canvas, legend, series, unit, digits) {
    this.canvas = canvas; this.legend = legend; this.series = series; this.unit = unit; this.digits = digits;
    this.t = []; this.v = series.map(() => []);
    this.draws = 0;  // redraws (the browser test reads it)
    this.samples = 0;  // samples received
  }
  clear() { this.t = []; this.v = this.series.map(() => []); this.dirty = true; }
  push(t, values) {
    if (this.t.length && t < this.t[this.t.length - 1]) this.clear();  // a reset
    if (this.t.length && t === this.t[this.t.length - 1]) return;
    this.t.push(t);
    this.samples += 1;
    values.forEach((x, i) => this.v[i].push(x));
    while (this.t.length && this.t[0] < t - PLOT_WINDOW_S) { this.t.shift(); this.v.forEach((a) => a.shift()); }
    this.dirty = true;
  }
  draw() {
    const g = beginDraw(this);
    if (!g) return;
    const c = this.canvas, W = c.width, H = c.height, pad = 4;
    if (this.t.length < 2) return;
    let lo = Infinity, hi = -Infinity;
    for (const a of this.v) for (const x of a) if (Number.isFinite(x)) { lo = Math.min(lo, x); hi = Math.max(hi, x); }
    if (!Number.isFinite(lo)) return;
    const span = Math.max(hi - lo, this.unit === "N" ? 20 : 0.02);
    const mid = (hi + lo) / 2;
    lo = mid - 0.55 * span; hi = mid + 0.55 * span;
    const t1 = this.t[this.t.length - 1], t0 = t1 - PLOT_WINDOW_S;
    const X = (t) => pad + (W - 2 * pad) * (t - t0) / PLOT_WINDOW_S, Y = (x) => H - pad - (H - 2 * pad) * (x - lo) / (hi - lo);
    g.strokeStyle = "#d8dce2"; g.lineWidth = 1;
    g.beginPath(); g.moveTo(pad, Y(mid)); g.lineTo(W - pad, Y(mid)); g.stroke();
    g.fillStyle = "#666"; g.font = "10px sans-serif";
    g.fillText(`${hi.toFixed(this.digits)} ${this.unit}`, pad + 2, 11);
    g.fillText(`${lo.toFixed(this.digits)} ${this.unit}`, pad + 2, H - 6);
    this.series.forEach((s, i) => {
      g.strokeStyle = s.color; g.lineWidth = 1.5; g.beginPath();
      let started = false;
      this.t.forEach((t, k) => {
        const x = this.v[i][k];
        if (!Number.isFinite(x)) { started = false; return; }
        if (started) g.lineTo(X(t), Y(x)); else { g.moveTo(X(t), Y(x)); started = true; }
      });
      g.stroke();
    });
    if (this.legend.children.length !== this.series.length + 1) {
      this.legend.replaceChildren(...this.series.map((s) => el("span", {style: `color:${s.color}; margin-right: 0.8em`})),
                                  el("span"));
    }
    this.series.forEach((s, i) => {
      setText(this.legend.children[i], `${s.label} ${fmt(this.v[i][this.v[i].length - 1], this.digits)} ${this.unit}`);
    });
    setText(this.legend.children[this.series.length], `t ${fmt(t1, 2)} s`);
  }
}
const PLOTS = {
  x: new TimePlot($("plot-x"), $("legend-x"), [{label: "ZMP x", color: "#1f9e3a"}, {label: "COG x", color: "#e07b00"}], "m", 3),
  y: new TimePlot($("plot-y"), $("legend-y"), [{label: "ZMP y", color: "#1f9e3a"}, {label: "COG y", color: "#e07b00"}], "m", 3),
  f: new TimePlot($("plot-f"), $("legend-f"), [{label: "right foot Fz", color: "#c8102e"}, {label: "left foot Fz", color: "#1c6fd1"}], "N", 0),
  cp: new CpPlot($("plot-cp"), $("legend-cp")),
};
window.hrp2Plots = PLOTS;
let lastRun = null;  // the tick and scene of the last state: a reset starts every plot's history again
export function plotSample(s) {
  if (lastRun && (s.tick < lastRun.tick || s.scene !== lastRun.scene)) for (const p of Object.values(PLOTS)) p.clear();
  lastRun = {tick: s.tick, scene: s.scene};
  const zmp = s.zmp || [], cog = s.cog || [], f = s.foot_forces_n || {};
  PLOTS.x.push(s.time, [zmp[0], cog[0]]);
  PLOTS.y.push(s.time, [zmp[1], cog[1]]);
  PLOTS.f.push(s.time, [f.rleg, f.lleg]);
  PLOTS.cp.push(s.time, s.capture_point, (s.emergency || {}).flag);
}
function drawPlots() {
  for (const p of Object.values(PLOTS)) p.draw();
  requestAnimationFrame(drawPlots);
}
requestAnimationFrame(drawPlots);
