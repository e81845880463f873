// The polar plot: f_r (· cos θi) in the plane of incidence, the light at θi, the mirror direction dashed.

import { canvasOf } from "../dom.js";
import { DEG, fmt } from "../numbers.js";
import { getSetting, num } from "../settings.js";
import { channelCurves, csvFrom, evalPanels, legend, nlWeights, planeDirections, plotFrame, setViewData, yLabel } from "./plot.js";

export function drawPolar() {
  const canvas = canvasOf("polar");
  const ctx = canvas.getContext("2d");
  const W = canvas.width, H = canvas.height;
  plotFrame(ctx, W, H);
  const N = 361;
  const cx = W / 2, cy = H - 24, R = Math.min(W / 2 - 30, H - 50);
  const d = planeDirections(N);
  const evals = evalPanels(d.wi, d.wo, N);
  const wts = nlWeights(d.wi, N);
  const curves = [].concat(...evals.map((e) => channelCurves(e.panel, e.f, N, wts)));
  const logScale = getSetting("scale") === "log";
  let vmax = 0;
  for (const c of curves) for (const y of c.ys) vmax = Math.max(vmax, y);
  if (!(vmax > 0)) vmax = 1;
  const radius = (y) => (!logScale ? R * y / vmax : y <= 0 ? 0 : R * Math.max(0, 1 + Math.log10(y / vmax) / 4));
  ctx.lineWidth = 1; ctx.strokeStyle = "#e3e3e3"; ctx.fillStyle = "#999";
  for (const fr of [0.25, 0.5, 0.75, 1]) { ctx.beginPath(); ctx.arc(cx, cy, R * fr, Math.PI, 2 * Math.PI); ctx.stroke(); }
  for (let g = -90; g <= 90; g += 15) {
    const a = g * DEG;
    ctx.beginPath(); ctx.moveTo(cx, cy); ctx.lineTo(cx + R * Math.sin(a), cy - R * Math.cos(a)); ctx.stroke();
    if (g % 30 === 0) ctx.fillText(`${g}°`, cx + (R + 6) * Math.sin(a) - 9, cy - (R + 8) * Math.cos(a) + 3);
  }
  ctx.strokeStyle = "#999";
  ctx.beginPath(); ctx.moveTo(cx - R - 10, cy); ctx.lineTo(cx + R + 10, cy); ctx.stroke();
  // the light comes in from the left at θi; the mirror direction is dashed on the right
  const ti = d.ti;
  ctx.setLineDash([4, 4]); ctx.strokeStyle = "#bbb";
  ctx.beginPath(); ctx.moveTo(cx, cy); ctx.lineTo(cx + R * Math.sin(ti), cy - R * Math.cos(ti)); ctx.stroke();
  ctx.setLineDash([]); ctx.strokeStyle = "#e8a317"; ctx.lineWidth = 2;
  const lx = cx - R * Math.sin(ti), ly = cy - R * Math.cos(ti);
  ctx.beginPath(); ctx.moveTo(lx, ly); ctx.lineTo(cx, cy); ctx.stroke();
  for (const c of curves) {
    ctx.strokeStyle = c.panel.color; ctx.lineWidth = 2; ctx.setLineDash(c.dash || []);
    ctx.beginPath();
    d.deg.forEach((a, k) => {
      const r = radius(c.ys[k]);
      const x = cx + r * Math.sin(a * DEG), y = cy - r * Math.cos(a * DEG);
      if (k === 0) ctx.moveTo(x, y); else ctx.lineTo(x, y);
    });
    ctx.stroke();
  }
  ctx.setLineDash([]); ctx.fillStyle = "#555";
  ctx.fillText(`outer ring: ${fmt(vmax)} ${yLabel()}${logScale ? " (log, 4 decades)" : ""} · light at θi = ${fmt(num("theta-i"))}°`, 8, 14);
  legend(ctx, curves, W);
  const peaks = curves.map((c) => d.deg[c.ys.indexOf(Math.max(...c.ys))]);
  setViewData("polar", Object.assign(csvFrom(["theta_o_deg"], [d.deg], evals, N), { peaks_deg: peaks, mirror_deg: num("theta-i") }));
}
