// The image slice: θh × θd at φd (Rusinkiewicz 1998), one tile per visible BRDF, by SLICE_MAIN.

import { canvasOf } from "../dom.js";
import { gl, glSize, U } from "../gl.js";
import { DEG, fmt, fromHalfDiff } from "../numbers.js";
import { getSetting, num } from "../settings.js";
import { bindMaterial, evaluateGPU, getProgram, intConstants, sourceKey } from "../brdfs.js";
import { visiblePanels } from "../panels.js";
import { blitTiles, csvFrom, evalPanels, fitTiles, reportDrawError } from "./plot.js";

export function drawSlice() {
  const canvas = canvasOf("slice");
  const ctx = canvas.getContext("2d");
  const list = visiblePanels();
  const T = fitTiles(canvas, list.length);
  ctx.fillStyle = "#222"; ctx.fillRect(0, 0, canvas.width, canvas.height);
  const size = T[0].w;
  glSize(size * list.length, size);
  gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  gl.disable(gl.DEPTH_TEST);
  const logScale = getSetting("scale") === "log";
  const ch = { rgb: 0, r: 1, g: 2, b: 3, lum: 4 }[getSetting("channel")];
  list.forEach((panel, i) => {
    try {
      let scale = Math.pow(2, num("exposure"));
      if (logScale) { // the top of the log scale: the largest value on a coarse grid of the slice
        const n = 32 * 32, wi = new Float32Array(3 * n), wo = new Float32Array(3 * n);
        for (let k = 0; k < n; k++) {
          const [a, b] = fromHalfDiff(((k % 32) + 0.5) / 32 * Math.PI / 2, (Math.floor(k / 32) + 0.5) / 32 * Math.PI / 2, num("phi-d") * DEG);
          wi.set(a, 3 * k); wo.set(b, 3 * k);
        }
        const f = evaluateGPU(panel.model, panel.params(), wi, wo);
        let m = 0; for (const x of f) m = Math.max(m, x);
        scale = m > 0 ? m * Math.pow(2, num("exposure")) : 1;
      }
      const prog = getProgram(sourceKey(panel.model), "slice", intConstants(panel.model, panel.params()));
      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
      gl.useProgram(prog);
      gl.viewport(i * size, 0, size, size);
      gl.uniform4f(U(prog, "bkw_viewport"), i * size, 0, size, size);
      gl.uniform1f(U(prog, "bkw_phi_d"), num("phi-d") * DEG);
      gl.uniform1f(U(prog, "bkw_scale"), scale);
      gl.uniform1i(U(prog, "bkw_log"), logScale ? 1 : 0);
      gl.uniform1i(U(prog, "bkw_channel"), ch);
      gl.uniform1i(U(prog, "bkw_ndotl"), getSetting("ndotl") ? 1 : 0);
      bindMaterial(prog, panel.model, panel.params());
      gl.drawArrays(gl.TRIANGLES, 0, 3);
    } catch (e) { reportDrawError(e); }
  });
  blitTiles(ctx, "slice", list, T, size, (panel) => `${panel.model}  (φd = ${fmt(num("phi-d"))}°)`);
}

// the slice's numbers: f_r on a 2° grid of (θh, θd) at the current φd, one row per grid point
export function sliceCSV() {
  const N = 46, n = N * N, wi = new Float32Array(3 * n), wo = new Float32Array(3 * n), th = [], td = [];
  for (let a = 0; a < N; a++) for (let b = 0; b < N; b++) {
    const k = a * N + b;
    th.push(2 * b); td.push(2 * a);
    const [x, y] = fromHalfDiff(2 * b * DEG, 2 * a * DEG, num("phi-d") * DEG);
    wi.set(x, 3 * k); wo.set(y, 3 * k);
  }
  const evals = evalPanels(wi, wo, n);
  return csvFrom(["theta_h_deg", "theta_d_deg"], [th, td], evals, n);
}
