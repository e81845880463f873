// The cartesian curves: f_r against θv in the plane of incidence, and against θh or θd
// (Rusinkiewicz's half/difference angles) at the other angles of the bar.

import { canvasOf } from "../dom.js";
import { DEG, fmt, fromHalfDiff } from "../numbers.js";
import { num } from "../settings.js";
import { channelCurves, csvFrom, drawCartesian, evalPanels, nlWeights, planeDirections, setViewData, yLabel } from "./plot.js";

export function drawThetaV() {
  const N = 361;
  const d = planeDirections(N);
  const evals = evalPanels(d.wi, d.wo, N);
  const wts = nlWeights(d.wi, N);
  const curves = [].concat(...evals.map((e) => channelCurves(e.panel, e.f, N, wts)));
  drawCartesian(canvasOf("theta_v"), d.deg, curves, "θv (signed, + on the mirror side)", yLabel(), { xticks: 30 });
  const peaks = curves.map((c) => d.deg[c.ys.indexOf(Math.max(...c.ys))]);
  setViewData("theta_v", Object.assign(csvFrom(["theta_v_deg"], [d.deg], evals, N), { peaks_deg: peaks }));
}

export function drawHalfDiffPlot(view) {
  const N = 181;
  const wi = new Float32Array(3 * N), wo = new Float32Array(3 * N), xs = [];
  const th = num("theta-h") * DEG, td = num("theta-d") * DEG, pd = num("phi-d") * DEG;
  for (let k = 0; k < N; k++) {
    const x = 90 * k / (N - 1);
    xs.push(x);
    const [a, b] = view === "theta_h" ? fromHalfDiff(x * DEG, td, pd) : fromHalfDiff(th, x * DEG, pd);
    wi.set(a, 3 * k); wo.set(b, 3 * k);
  }
  const evals = evalPanels(wi, wo, N);
  const wts = nlWeights(wi, N);
  const curves = [].concat(...evals.map((e) => channelCurves(e.panel, e.f, N, wts)));
  const label = view === "theta_h" ? `θh (θd = ${fmt(num("theta-d"))}°, φd = ${fmt(num("phi-d"))}°)`
    : `θd (θh = ${fmt(num("theta-h"))}°, φd = ${fmt(num("phi-d"))}°)`;
  drawCartesian(canvasOf(view), xs, curves, label, yLabel(), {});
  setViewData(view, csvFrom([view === "theta_h" ? "theta_h_deg" : "theta_d_deg"], [xs], evals, N));
}
