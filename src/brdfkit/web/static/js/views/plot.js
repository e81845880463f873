// What the plot views share: frames, axes and legends on a 2D canvas, the curves of the visible
// BRDFs (evaluated on the GPU), the CSV table of a plot, the tiles of the per-pixel views.

import * as store from "../store.js";
import { showError } from "../dom.js";
import { glCanvas } from "../gl.js";
import { DEG, fmt } from "../numbers.js";
import { getSetting, num } from "../settings.js";
import { evaluateGPU } from "../brdfs.js";
import { visiblePanels } from "../panels.js";

/** Keep a view's numbers (CSV, window.brdfkit.data). */
export function setViewData(view, data) { store.update("viewData", (d) => { d[view] = data; }); }

export function channelOf(f, k, ch) {
  const r = f[3 * k], g = f[3 * k + 1], b = f[3 * k + 2];
  if (ch === "r") return r;
  if (ch === "g") return g;
  if (ch === "b") return b;
  return 0.2126 * r + 0.7152 * g + 0.0722 * b;
}
// the curves of one BRDF for a plot: [{label, ys, dash}] per channel choice
export function channelCurves(panel, f, n, weight) {
  const ch = getSetting("channel");
  const chans = ch === "rgb" ? ["r", "g", "b"] : [ch];
  return chans.map((c, i) => ({
    panel, label: `${panel.model}${chans.length > 1 ? " " + c : ""}`, dash: [[], [6, 3], [2, 3]][i],
    ys: Array.from({ length: n }, (_, k) => channelOf(f, k, c) * (weight ? weight[k] : 1)),
  }));
}
export function rgbColumns(panel) { return [`${panel.model}_r`, `${panel.model}_g`, `${panel.model}_b`]; }


export function plotFrame(ctx, W, H) {
  ctx.fillStyle = "#fff"; ctx.fillRect(0, 0, W, H);
  ctx.font = "13px system-ui, sans-serif";
}
export function legend(ctx, curves, W) {
  let y = 14;
  const seen = new Set();
  for (const c of curves) {
    if (seen.has(c.label)) continue;
    seen.add(c.label);
    ctx.strokeStyle = c.panel.color; ctx.lineWidth = 2; ctx.setLineDash(c.dash || []);
    ctx.beginPath(); ctx.moveTo(W - 215, y - 4); ctx.lineTo(W - 190, y - 4); ctx.stroke();
    ctx.setLineDash([]); ctx.fillStyle = "#333";
    ctx.fillText(c.label, W - 185, y, 180);
    y += 15;
  }
}

// a cartesian plot: x from xs, one line per curve; log scale over 4 decades below the maximum
export function drawCartesian(canvas, xs, curves, xlabel, ylabel, opts) {
  const ctx = canvas.getContext("2d");
  const W = canvas.width, H = canvas.height;
  plotFrame(ctx, W, H);
  const L = 58, R = 12, T = 12, B = 34;
  const logScale = getSetting("scale") === "log" && !(opts && opts.linear);
  let vmax = 0;
  for (const c of curves) for (const y of c.ys) if (isFinite(y)) vmax = Math.max(vmax, y);
  if (!(vmax > 0)) vmax = 1;
  if (opts && opts.ymax) vmax = Math.max(vmax, opts.ymax);
  const vmin = logScale ? vmax * 1e-4 : 0;
  const x0 = xs[0], x1 = xs[xs.length - 1];
  const px = (x) => L + (x - x0) / (x1 - x0) * (W - L - R);
  const py = (y) => {
    const t = logScale ? (y <= vmin ? 0 : Math.log10(y / vmin) / 4) : y / vmax;
    return H - B - Math.min(1.02, t) * (H - B - T);
  };
  ctx.strokeStyle = "#e3e3e3"; ctx.fillStyle = "#666"; ctx.lineWidth = 1;
  const xt = opts && opts.xticks || 15;
  for (let x = Math.ceil(x0 / xt) * xt; x <= x1 + 1e-9; x += xt) {
    ctx.beginPath(); ctx.moveTo(px(x), T); ctx.lineTo(px(x), H - B); ctx.stroke();
    ctx.fillText(`${x}°`, px(x) - 8, H - B + 14);
  }
  const yt = logScale ? [0, 1, 2, 3, 4].map((d) => vmin * Math.pow(10, d)) : [0, 0.25, 0.5, 0.75, 1].map((f) => f * vmax);
  for (const y of yt) {
    ctx.beginPath(); ctx.moveTo(L, py(y)); ctx.lineTo(W - R, py(y)); ctx.stroke();
    ctx.fillText(fmt(y), 4, py(y) + 4);
  }
  ctx.fillStyle = "#333";
  ctx.fillText(xlabel, W / 2 - 20, H - 6);
  ctx.save(); ctx.translate(12, H / 2 + 30); ctx.rotate(-Math.PI / 2); ctx.fillText(ylabel, 0, 0); ctx.restore();
  ctx.save();
  ctx.beginPath(); ctx.rect(L, T - 2, W - L - R, H - B - T + 4); ctx.clip();
  for (const c of curves) {
    ctx.strokeStyle = c.panel.color; ctx.lineWidth = 2; ctx.setLineDash(c.dash || []);
    ctx.beginPath();
    xs.forEach((x, k) => { const X = px(x), Y = py(c.ys[k]); if (k === 0) ctx.moveTo(X, Y); else ctx.lineTo(X, Y); });
    ctx.stroke();
  }
  ctx.restore();
  ctx.setLineDash([]);
  legend(ctx, curves, W);
  return { vmax };
}

export const yLabel = () => (getSetting("ndotl") ? "f_r · cos θi" : "f_r [1/sr]");

// directions in the plane of incidence: wi at (θi, φi), wo at signed angle a in the same plane
export function planeDirections(n) {
  const ti = num("theta-i") * DEG, ph = num("phi-i") * DEG;
  const c = Math.cos(ph), s = Math.sin(ph);
  const wi = new Float32Array(3 * n), wo = new Float32Array(3 * n), deg = [];
  const wiv = [Math.sin(ti) * c, Math.sin(ti) * s, Math.cos(ti)];
  for (let k = 0; k < n; k++) {
    const a = (-89.9 + 179.8 * k / (n - 1)) * DEG; // a > 0: on the mirror side (away from the light)
    deg.push(a / DEG);
    wi.set(wiv, 3 * k);
    wo.set([-Math.sin(a) * c, -Math.sin(a) * s, Math.cos(a)], 3 * k);
  }
  return { wi, wo, deg, ti };
}


export function nlWeights(wi, n) {
  if (!getSetting("ndotl")) return null;
  return Array.from({ length: n }, (_, k) => Math.max(0, wi[3 * k + 2]));
}

export function evalPanels(wi, wo, n) {
  const out = [];
  for (const panel of visiblePanels()) {
    try { out.push({ panel, f: evaluateGPU(panel.model, panel.params(), wi, wo) }); } catch (e) { reportDrawError(e); }
  }
  return out;
}
let lastDrawError = null;
export function reportDrawError(e) {
  const m = String(e.message || e);
  if (m !== lastDrawError) { lastDrawError = m; showError("drawing failed: " + m); }
}
export function csvFrom(header, xcols, evals, n) {
  const rows = [];
  for (let k = 0; k < n; k++) {
    const row = xcols.map((c) => c[k]);
    for (const e of evals) row.push(e.f[3 * k], e.f[3 * k + 1], e.f[3 * k + 2]);
    rows.push(row);
  }
  return { header: header.concat(...evals.map((e) => rgbColumns(e.panel))), rows };
}

// a row of square tiles, one per visible BRDF, each with a label line under it (LABEL_H),
// in a canvas of the view's width; the canvas's height follows the row (at most its height
// in index.html), so that no empty band is left below the tiles
const LABEL_H = 18;
export function fitTiles(canvas, count) {
  if (!canvas.dataset.maxHeight) canvas.dataset.maxHeight = String(canvas.height);
  const W = canvas.width, H = +canvas.dataset.maxHeight;
  const n = Math.max(1, count);
  const w = Math.max(1, Math.min(Math.floor(W / n), H - LABEL_H));
  if (canvas.height !== w + LABEL_H) canvas.height = w + LABEL_H;
  const x0 = Math.floor((W - n * w) / 2);
  return Array.from({ length: n }, (_, i) => ({ x: x0 + i * w, y: 0, w, h: w }));
}

// copy each panel's tile (drawn side by side along the bottom of the GL canvas, `size` pixels square)
// onto the view's tiles T, with label(panel) beneath in the panel's colour; keep the tiles as the view's data
export function blitTiles(ctx, view, list, T, size, label) {
  list.forEach((panel, i) => {
    ctx.drawImage(glCanvas, i * size, glCanvas.height - size, size, size, T[i].x, 0, size, size);
    ctx.fillStyle = panel.color; ctx.font = "13px system-ui, sans-serif";
    ctx.fillText(label(panel), T[i].x + 3, size + 14, size - 6);
  });
  setViewData(view, { tiles: T.slice(0, list.length), models: list.map((p) => p.model) });
}
