// The lit object under an environment map: the renderer's ibl.glsl, progressive (one pass of
// IBL_SPP samples per pixel per frame, accumulated here until obj-ibl-spp).

import * as store from "../store.js";
import { showError } from "../dom.js";
import { gl, makeFloatTexture, U } from "../gl.js";
import { eyeToMap, objectMatrices, srgbEncode } from "../numbers.js";
import { fetchJSON } from "../net.js";
import { num } from "../settings.js";
import { bindMaterial, getProgram, intConstants, kindOf, sourceKey } from "../brdfs.js";
import { visiblePanels } from "../panels.js";
import { getState } from "../urlstate.js";

/** The last environment-lit image (ImageData), or null when the object was drawn by GL. */
export const iblImage = () => ibl.image;
export function clearIblImage() { ibl.image = null; }
/** Whether another pass is due (the draw loop asks for it next frame), and forget that. */
export const iblPending = () => ibl.pending;
export function clearIblPending() { ibl.pending = false; }

// ---- image-based lighting: the renderer's ibl.glsl, progressive (one pass of IBL_SPP per frame) ----
const IBL_SPP = 8;  // samples per pixel per pass, as the renderer's IBL_SPP_PER_PASS
const iblMax = () => Math.max(IBL_SPP, Math.round(num("obj-ibl-spp") / IBL_SPP) * IBL_SPP);
const envCache = {}, samplerCache = {};
const ibl = { key: null, acc: null, spp: 0, fbo: null, color: null, depth: null, w: 0, h: 0, pending: false };
function envTextures(name) {
  if (envCache[name] && envCache[name].tex) return envCache[name];
  if (!envCache[name]) {
    envCache[name] = { loading: true };
    fetch("/api/env?name=" + encodeURIComponent(name)).then(async (r) => {
      if (!r.ok) throw new Error((await r.json()).error);
      const buf = await r.arrayBuffer();
      const head = new Int32Array(buf, 0, 6), extra = new Float32Array(buf, 24, 10);
      let off = 64;
      const tex = [[head[0], head[1], 4], [head[2], head[3], 1], [head[4], head[5], 1]].map(([hh, ww, comps]) => {
        const data = new Float32Array(buf, off, hh * ww * comps);
        off += hh * ww * comps * 4;
        const t = gl.createTexture();
        gl.bindTexture(gl.TEXTURE_2D, t);
        for (const p of [gl.TEXTURE_MIN_FILTER, gl.TEXTURE_MAG_FILTER]) gl.texParameteri(gl.TEXTURE_2D, p, gl.NEAREST);
        for (const p of [gl.TEXTURE_WRAP_S, gl.TEXTURE_WRAP_T]) gl.texParameteri(gl.TEXTURE_2D, p, gl.CLAMP_TO_EDGE);
        gl.texImage2D(gl.TEXTURE_2D, 0, comps === 4 ? gl.RGBA32F : gl.R32F, ww, hh, 0, comps === 4 ? gl.RGBA : gl.RED, gl.FLOAT, data);
        return t;
      });
      envCache[name] = { tex, worldToMap: Array.from(extra.slice(0, 9)), strength: extra[9] };
      store.requestDraw();
    }).catch((e) => { envCache[name] = { error: e.message }; showError(`environment ${name}: ${e.message}`); });
  }
  return null;
}
function samplerOf(panel) {
  const key = panel.model + JSON.stringify(panel.params());
  if (samplerCache[key] && samplerCache[key].u) return samplerCache[key].u;
  if (!samplerCache[key]) {
    samplerCache[key] = { loading: true };
    const q = new URLSearchParams({ model: panel.model, params: JSON.stringify(panel.params()) });
    fetchJSON("/api/ibl/sampler?" + q.toString()).then((u) => { samplerCache[key] = { u }; store.requestDraw(); })
      .catch(() => { samplerCache[key] = { u: { bki_lobe: 0, bki_lobe_params: [0, 0], bki_diffuse_prob: 1 } }; store.requestDraw(); });
  }
  return null;
}
export function renderObjectIBL(mesh, w, h, envName, matSel) {
  if (matSel.startsWith("gl:")) return "image-based lighting needs a BRDF material (the fixed-function model has no environment term)";
  const i = parseInt(matSel.slice(5), 10);
  const panel = visiblePanels()[i];
  if (!panel) return `no visible BRDF number ${i + 1}`;
  const env = envTextures(envName);
  const smp = kindOf(panel.model) === "analytic" || kindOf(panel.model) === "nbrdf" ? samplerOf(panel)
    : { bki_lobe: 0, bki_lobe_params: [0, 0], bki_diffuse_prob: 1 };
  if (!env || !smp) return "loading the environment…";
  const st = getState();
  delete st.view["obj-ibl-spp"]; delete st.view.exposure;  // more samples or another exposure: keep what is there
  const key = JSON.stringify([st, w, h, mesh.name, mesh.n]);
  if (key !== ibl.key || ibl.w !== w || ibl.h !== h) {
    ibl.key = key; ibl.spp = 0; ibl.acc = new Float32Array(w * h * 4);
    if (ibl.w !== w || ibl.h !== h) {
      for (const o of [ibl.color]) if (o) gl.deleteTexture(o);
      if (ibl.depth) gl.deleteRenderbuffer(ibl.depth);
      if (!ibl.fbo) ibl.fbo = gl.createFramebuffer();
      ibl.color = makeFloatTexture(w, h, null);
      ibl.depth = gl.createRenderbuffer();
      gl.bindRenderbuffer(gl.RENDERBUFFER, ibl.depth);
      gl.renderbufferStorage(gl.RENDERBUFFER, gl.DEPTH_COMPONENT24, w, h);
      gl.bindFramebuffer(gl.FRAMEBUFFER, ibl.fbo);
      gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, ibl.color, 0);
      gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.DEPTH_ATTACHMENT, gl.RENDERBUFFER, ibl.depth);
      ibl.w = w; ibl.h = h;
    }
  }
  if (ibl.spp < iblMax()) {
    const prog = getProgram(sourceKey(panel.model), "ibl-phong", intConstants(panel.model, panel.params()));
    gl.bindFramebuffer(gl.FRAMEBUFFER, ibl.fbo);
    gl.viewport(0, 0, w, h);
    gl.clearColor(0, 0, 0, 0); gl.clearDepth(1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.useProgram(prog);
    const M = objectMatrices(store.get("orbit").object, w, h);
    gl.uniformMatrix4fv(U(prog, "bkr_modelview"), false, M.mv);
    gl.uniformMatrix4fv(U(prog, "bkr_projection"), false, M.proj);
    gl.uniformMatrix3fv(U(prog, "bkr_normal_matrix"), false, M.nm);
    bindMaterial(prog, panel.model, panel.params());
    env.tex.forEach((t, k) => {
      gl.activeTexture(gl.TEXTURE4 + k); gl.bindTexture(gl.TEXTURE_2D, t);
      gl.uniform1i(U(prog, ["bki_env", "bki_env_marg", "bki_env_cond"][k]), 4 + k);
    });
    gl.activeTexture(gl.TEXTURE0);
    // eye -> map: the map's rotation after the inverse of the modelview's (a rotation here), as ibl.eye_to_map
    const R = M.nm, W2M = env.worldToMap; // R column-major 3x3 (eye = R · world); W2M row-major
    const e2m = eyeToMap(R, W2M);
    gl.uniformMatrix3fv(U(prog, "bki_eye_to_map"), false, e2m);
    gl.uniform1f(U(prog, "bki_strength"), env.strength);
    gl.uniform1i(U(prog, "bki_spp"), IBL_SPP);
    gl.uniform1i(U(prog, "bki_pass"), ibl.spp / IBL_SPP);
    gl.uniform1i(U(prog, "bki_lobe"), smp.bki_lobe);
    gl.uniform2fv(U(prog, "bki_lobe_params"), smp.bki_lobe_params);
    gl.uniform1f(U(prog, "bki_diffuse_prob"), smp.bki_diffuse_prob);
    const A = prog._attr;
    for (const [loc, buf] of [[A.position, mesh.pos], [A.normal, mesh.nor], [A.tangent, mesh.tan]]) {
      if (loc < 0) continue;
      gl.bindBuffer(gl.ARRAY_BUFFER, buf); gl.enableVertexAttribArray(loc); gl.vertexAttribPointer(loc, 3, gl.FLOAT, false, 0, 0);
    }
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, mesh.idx);
    gl.enable(gl.DEPTH_TEST); gl.depthFunc(gl.LESS);
    gl.drawElements(gl.TRIANGLES, mesh.n, gl.UNSIGNED_INT, 0);
    gl.disable(gl.DEPTH_TEST);
    for (const loc of [A.position, A.normal, A.tangent]) if (loc >= 0) gl.disableVertexAttribArray(loc);
    const img = new Float32Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.FLOAT, img);
    for (let k = 0; k < img.length; k++) ibl.acc[k] += img[k] * IBL_SPP;
    ibl.spp += IBL_SPP;
  }
  // show: mean radiance · 2^exposure, sRGB-encoded (rows flipped: GL's first row is the bottom)
  const scale = Math.pow(2, num("exposure")) / ibl.spp;
  const out = new ImageData(w, h);
  const bg = [0.09, 0.09, 0.1].map((x) => Math.round(x * 255));
  for (let y = 0; y < h; y++) for (let x = 0; x < w; x++) {
    const s = 4 * ((h - 1 - y) * w + x), d = 4 * (y * w + x);
    const cov = ibl.acc[s + 3] > 0;
    for (let c = 0; c < 3; c++) {
      const v = ibl.acc[s + c] * scale;
      out.data[d + c] = cov ? Math.round(255 * srgbEncode(Math.min(1, Math.max(0, isFinite(v) ? v : 0)))) : bg[c];
    }
    out.data[d + 3] = 255;
  }
  ibl.image = out;
  gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  if (ibl.spp < iblMax()) ibl.pending = true;
  return `${panel.model} · ${mesh.name} · environment ${envName} (no shadows; the map is not drawn behind) · `
    + `${ibl.spp} of ${iblMax()} samples per pixel (MIS of the BRDF's sampler and the map's luminance), sRGB`;
}
export const iblDone = () => ibl.spp >= iblMax();
