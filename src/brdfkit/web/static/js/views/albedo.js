// The directional albedo ρ(θi): GPU quadrature of the model's GLSL, or the engine on the server.

import * as store from "../store.js";
import { $, canvasOf, showError } from "../dom.js";
import { DEG, sph } from "../numbers.js";
import { fetchJSON } from "../net.js";
import { getSetting } from "../settings.js";
import { evaluateGPU, kindOf } from "../brdfs.js";
import { visiblePanels } from "../panels.js";
import { channelCurves, csvFrom, drawCartesian, reportDrawError, setViewData } from "./plot.js";

// albedo: GPU quadrature (cosine-weighted midpoint grid), or the engine through the server
const ALB_ANGLES = 46, ALB_S = 48;
const albedoCache = {};
function albedoGPU(panel) {
  const n = ALB_ANGLES * ALB_S * ALB_S;
  const wi = new Float32Array(3 * n), wo = new Float32Array(3 * n);
  const thetas = [];
  let k = 0;
  for (let a = 0; a < ALB_ANGLES; a++) {
    const t = 89 * a / (ALB_ANGLES - 1);
    thetas.push(t);
    const w = sph(t * DEG, 0);
    for (let i = 0; i < ALB_S; i++) {
      for (let j = 0; j < ALB_S; j++) {
        const u = (i + 0.5) / ALB_S, v = (j + 0.5) / ALB_S;
        const r = Math.sqrt(u), p = 2 * Math.PI * v;
        wi.set(w, 3 * k);
        wo.set([r * Math.cos(p), r * Math.sin(p), Math.sqrt(1 - u)], 3 * k);
        k++;
      }
    }
  }
  const f = evaluateGPU(panel.model, panel.params(), wi, wo);
  const rgb = [];
  for (let a = 0; a < ALB_ANGLES; a++) {
    const s = [0, 0, 0];
    for (let q = 0; q < ALB_S * ALB_S; q++) for (let c = 0; c < 3; c++) s[c] += f[3 * (a * ALB_S * ALB_S + q) + c];
    rgb.push(s.map((x) => x * Math.PI / (ALB_S * ALB_S)));
  }
  return { thetas, rgb };
}
function albedoEngine(panel) {
  const key = panel.model + JSON.stringify(panel.params());
  const hit = albedoCache[key];
  if (hit && hit.data) return hit.data;
  if (!hit) {
    albedoCache[key] = { pending: true };
    const q = new URLSearchParams({ model: panel.model, params: JSON.stringify(panel.params()), n: String(ALB_ANGLES) });
    fetchJSON("/api/albedo?" + q.toString()).then((b) => {
      albedoCache[key] = { data: { thetas: b.theta_deg, rgb: b.rgb } };
      store.requestDraw();
    }).catch((e) => { albedoCache[key] = { data: null, error: e.message }; showError(`albedo of ${panel.model}: ${e.message}`); });
  }
  return null;
}
export function drawAlbedo() {
  const method = getSetting("albedo-method");
  const curves = [], evals = [];
  let xs = null, waiting = 0;
  for (const panel of visiblePanels()) {
    let d = null;
    try { d = method === "gpu" ? albedoGPU(panel) : albedoEngine(panel); } catch (e) { reportDrawError(e); }
    if (!d) { waiting++; continue; }
    if ((kindOf(panel.model) === "merl" || kindOf(panel.model) === "table") && method !== "gpu") continue;
    xs = d.thetas;
    const f = Float32Array.from(d.rgb.flat());
    evals.push({ panel, f });
    curves.push(...channelCurves(panel, f, d.thetas.length, null));
  }
  if (!xs) xs = Array.from({ length: ALB_ANGLES }, (_, a) => 89 * a / (ALB_ANGLES - 1));
  drawCartesian(canvasOf("albedo"), xs, curves, "θi", "directional albedo ρ", { linear: true, ymax: 1 });
  $("#albedo-note").textContent = method === "gpu"
    ? `GPU: each of the model's GLSL values f_r(wi, wo_k) on ${ALB_S}×${ALB_S} cosine-weighted midpoint directions, ρ = π/N Σ f_r (under-resolves lobes narrower than ~2°; use the engine for those). Mirror (delta) parts are not included.`
    : `Engine: brdfkit.analysis.albedo on the server (adaptive quadrature, level=fast)${waiting ? ` — computing ${waiting}…` : ""}.`;
  setViewData("albedo", csvFrom(["theta_i_deg"], [xs], evals, xs.length));
}
