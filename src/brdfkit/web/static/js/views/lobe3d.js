// The 3D lobe: f_r over the hemisphere of wo as a wire surface, orbited with the mouse.

import * as store from "../store.js";
import { canvasOf } from "../dom.js";
import { DEG, fmt, sph } from "../numbers.js";
import { getSetting, num } from "../settings.js";
import { channelCurves, csvFrom, evalPanels, legend, nlWeights, plotFrame, setViewData, yLabel } from "./plot.js";

export function drawLobe3D() {
  const canvas = canvasOf("lobe3d");
  const ctx = canvas.getContext("2d");
  const W = canvas.width, H = canvas.height;
  plotFrame(ctx, W, H);
  const NT = 24, NP = 72;
  const n = NT * NP;
  const ti = num("theta-i") * DEG, pi = num("phi-i") * DEG;
  const wiv = sph(ti, pi);
  const wi = new Float32Array(3 * n), wo = new Float32Array(3 * n), dirs = [];
  let k = 0;
  for (let a = 0; a < NT; a++) {
    for (let b = 0; b < NP; b++) {
      const v = sph(89.5 * DEG * a / (NT - 1), 2 * Math.PI * b / NP);
      wi.set(wiv, 3 * k); wo.set(v, 3 * k); dirs.push(v); k++;
    }
  }
  const evals = evalPanels(wi, wo, n);
  const wts = nlWeights(wi, n);
  const curves = [].concat(...evals.map((e) => channelCurves(e.panel, e.f, n, wts)));
  const logScale = getSetting("scale") === "log";
  let vmax = 0;
  for (const c of curves) for (const y of c.ys) vmax = Math.max(vmax, y);
  if (!(vmax > 0)) vmax = 1;
  const rad = (y) => (!logScale ? y / vmax : y <= 0 ? 0 : Math.max(0, 1 + Math.log10(y / vmax) / 4));
  const o = store.get("orbit").lobe3d;
  const cy = Math.cos(o.yaw * DEG), sy = Math.sin(o.yaw * DEG), cp = Math.cos(o.pitch * DEG), sp = Math.sin(o.pitch * DEG);
  const S = Math.min(W, H) * 0.42 * o.zoom;
  const proj = (p) => { // z up; yaw about z, then pitch toward the viewer
    const x = cy * p[0] - sy * p[1], y = sy * p[0] + cy * p[1];
    const Y = cp * p[2] - sp * y;
    return [W / 2 + S * x, H * 0.62 - S * Y];
  };
  // the surface disc and the axes
  ctx.strokeStyle = "#ddd"; ctx.lineWidth = 1;
  ctx.beginPath();
  for (let b = 0; b <= 72; b++) { const q = proj([Math.cos(b * 5 * DEG), Math.sin(b * 5 * DEG), 0]); if (b) ctx.lineTo(...q); else ctx.moveTo(...q); }
  ctx.stroke();
  for (const [ax, lab] of [[[1, 0, 0], "x (t)"], [[0, 1, 0], "y"], [[0, 0, 1], "z (n)"]]) {
    const a = proj([0, 0, 0]), b = proj(ax);
    ctx.strokeStyle = "#999"; ctx.beginPath(); ctx.moveTo(...a); ctx.lineTo(...b); ctx.stroke();
    ctx.fillStyle = "#777"; ctx.fillText(lab, b[0] + 3, b[1] - 3);
  }
  const l0 = proj([0, 0, 0]), l1 = proj(wiv.map((x) => x * 1.1));
  ctx.strokeStyle = "#e8a317"; ctx.lineWidth = 2; ctx.beginPath(); ctx.moveTo(...l1); ctx.lineTo(...l0); ctx.stroke();
  for (const c of curves) {
    const pts = dirs.map((v, q) => { const r = rad(c.ys[q]); return proj([v[0] * r, v[1] * r, v[2] * r]); });
    ctx.strokeStyle = c.panel.color; ctx.lineWidth = 1; ctx.setLineDash(c.dash || []);
    ctx.beginPath();
    for (let a = 0; a < NT; a++) for (let b = 0; b <= NP; b++) {
      const p = pts[a * NP + (b % NP)];
      if (b === 0) ctx.moveTo(...p); else ctx.lineTo(...p);
    }
    for (let b = 0; b < NP; b += 3) for (let a = 0; a < NT; a++) {
      const p = pts[a * NP + b];
      if (a === 0) ctx.moveTo(...p); else ctx.lineTo(...p);
    }
    ctx.stroke();
  }
  ctx.setLineDash([]); ctx.fillStyle = "#555";
  ctx.fillText(`radius: ${yLabel()}, max ${fmt(vmax)}${logScale ? " (log, 4 decades)" : ""}; light (θi, φi) = (${fmt(num("theta-i"))}°, ${fmt(num("phi-i"))}°)`, 8, H - 8);
  legend(ctx, curves, W);
  const th = dirs.map((v) => Math.acos(Math.min(1, v[2])) / DEG), ph = dirs.map((v) => (Math.atan2(v[1], v[0]) / DEG + 360) % 360);
  setViewData("lobe3d", csvFrom(["theta_o_deg", "phi_o_deg"], [th, ph], evals, n));
}
