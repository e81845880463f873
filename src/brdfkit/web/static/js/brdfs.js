// The BRDFs the page knows (analytic models, built-in measured materials, dropped MERL, RGL,
// UTIA and .brdf files), their GLSL programs, and evaluation on the GPU: brdf() for direction pairs
// read from float textures into an RGBA32F target and read back (every plot, the albedo
// quadrature, window.brdfkit.eval).

import * as store from "./store.js";
import { gl, compileProgram, U, makeFloatTexture } from "./gl.js";
import { VERT, SPHERE_MAIN, SLICE_MAIN, EVAL_MAIN, specialise, pipelineSources } from "./shaders.js";
import { effectiveParams } from "./numbers.js";
import { fetchText, fetchJSON } from "./net.js";

const nbrdfWeights = {};  // material -> Float32Array(844): u_nbrdf[211] of nbrdf.glsl (only this module reads them)

/** "analytic" | "merl" | "table" (a dropped RGL/UTIA/.bin file) | "brdf" | "nbrdf", or null for a
 * name the page does not know. */
export function kindOf(name) {
  if (store.get("modelInfo")[name]) return "analytic";
  if (store.get("merlTables")[name]) return "merl";
  if (store.get("tableFiles")[name]) return "table";
  if (store.get("brdfFiles")[name]) return "brdf";
  if (store.get("measuredNames").includes(name)) return "nbrdf";
  return null;
}

/** The key of the GLSL source a BRDF uses (in the store's `sources`). */
export function sourceKey(name) {
  const k = kindOf(name);
  if (k === "analytic") return name;
  if (k === "nbrdf") return "__nbrdf";
  if (k === "merl") return "__merl";
  if (k === "table") return store.get("tableFiles")[name].key;
  if (k === "brdf") return store.get("brdfFiles")[name].key;
  throw new Error(`unknown BRDF '${name}'`);
}

/** The /api/models row of a BRDF (a measured one: no parameters). */
export function infoOf(name) {
  const k = kindOf(name);
  if (k === "analytic") return store.get("modelInfo")[name];
  if (k === "brdf") return store.get("brdfFiles")[name].info;
  if (k === "table") return store.get("tableFiles")[name].info;
  return { name, title: k === "merl" ? "MERL table (dropped file), nearest bin" : "measured material (Neural-BRDF network)",
    reference: "", params: [] };
}

// The per-pixel views compile a model once per combination of its integer parameters
// (choices, booleans): their `uniform int u_x;` becomes `const int u_x = v;`, the rest of
// the model's GLSL unchanged, so the compiler drops the branches not taken. A software
// renderer (SwiftShader) otherwise runs every side of a branch on a uniform, tables of
// unused options included (microfacet's sphere at 750x750: 4.6 s -> 0.11 s a frame).
export function intConstants(name, params) {
  const k = kindOf(name);
  if (k !== "analytic" && k !== "brdf") return null;
  const info = infoOf(name);
  const eff = effectiveParams(info, params);
  const out = {};
  for (const p of info.params) {
    if (!p.uniform || p.uniform.type !== "int") continue;
    out[p.uniform.name] = intUniform(p, eff[p.name]);
  }
  return Object.keys(out).length ? out : null;
}

/** The int a choice, bool or int parameter's uniform takes (brdfkit.render.glsl.uniform_values). */
function intUniform(p, v) {
  if (p.kind === "choice") return Math.max(0, p.choices.indexOf(v));
  if (p.kind === "bool") return v === true || v === 1 || v === "true" ? 1 : 0;
  return Math.round(+v);
}

function sourceOf(key, consts) {
  const src = store.get("sources")[key];
  if (src === undefined) throw new Error(`no GLSL source for '${key}'`);
  return specialise(src, consts);
}

/** A compiled program: kind "eval" | "sphere" | "slice" | "obj-flat" | "ibl-phong" | "gl-gouraud" ...;
 * consts: intConstants(...) or null. A failure is remembered and thrown again. */
export function getProgram(key, kind, consts) {
  const programs = store.get("programs");
  const id = key + "|" + kind + (consts ? "|" + JSON.stringify(consts) : "");
  if (programs[id]) {
    if (programs[id].error) throw new Error(programs[id].error);
    return programs[id];
  }
  try {
    let prog;
    if (kind === "eval" || kind === "sphere" || kind === "slice") {
      const main = kind === "eval" ? EVAL_MAIN : kind === "sphere" ? SPHERE_MAIN : SLICE_MAIN;
      prog = compileProgram(VERT, sourceOf(key, consts) + main);
    } else {
      prog = pipelineProgram(key, kind, consts);
    }
    programs[id] = prog;
    return prog;
  } catch (e) {
    programs[id] = { error: `${key} (${kind}): ${e.message.split("\n")[0]}` };
    throw new Error(programs[id].error);
  }
}

/** Forget the programs of a source (a file loaded again). */
export function dropPrograms(key) {
  const programs = store.get("programs");
  for (const k of Object.keys(programs)) if (k.startsWith(key + "|")) delete programs[k];
}

function pipelineProgram(key, kind, consts) {
  const brdf = kind.startsWith("gl-") ? "" : sourceOf(key, consts);
  const { vs, fs } = pipelineSources(kind, store.get("shaderFiles"), brdf);
  const prog = compileProgram(vs, fs);
  prog._attr = {
    position: gl.getAttribLocation(prog, "in_position"),
    normal: gl.getAttribLocation(prog, "in_normal"),
    tangent: gl.getAttribLocation(prog, "in_tangent"),
  };
  return prog;
}

/** The uniform values of a parameter set (a plain object, as for /api/eval). */
function setModelUniforms(prog, info, values) {
  for (const p of info.params) {
    const loc = U(prog, p.uniform.name);
    let v = values[p.name];
    if (loc === null || v === null || v === undefined) continue;
    if (p.kind === "scalar") gl.uniform1f(loc, +v);
    else if (p.kind === "rgb") {
      if (!Array.isArray(v)) v = [v, v, v];
      gl.uniform3f(loc, +v[0], +v[1], +v[2]);
    } else gl.uniform1i(loc, intUniform(p, v));
  }
}

/** Bind what a BRDF needs: its parameters, its network weights or its table. */
export function bindMaterial(prog, name, params) {
  const k = kindOf(name);
  if (k === "analytic" || k === "brdf") {
    const info = infoOf(name);
    setModelUniforms(prog, info, effectiveParams(info, params));
  } else if (k === "nbrdf") {
    const w = nbrdfWeights[name];
    if (!w) throw new Error(`measured material '${name}' is not loaded yet`);
    gl.uniform4fv(U(prog, "u_nbrdf[0]") || U(prog, "u_nbrdf"), w);
  } else if (k === "merl") {
    gl.activeTexture(gl.TEXTURE3);
    gl.bindTexture(gl.TEXTURE_3D, store.get("merlTables")[name].texture);
    gl.uniform1i(U(prog, "u_table"), 3);
    gl.uniform1i(U(prog, "u_interpolation"), 0);
    gl.activeTexture(gl.TEXTURE0);
  } else if (k === "table") {  // units and uniforms as the server's brdfkit.render.tables says
    const f = store.get("tableFiles")[name];
    for (const t of f.textures) {
      gl.activeTexture(gl.TEXTURE0 + t.unit);
      gl.bindTexture(t.target, t.texture);
      gl.uniform1i(U(prog, t.uniform), t.unit);
    }
    for (const [u, v] of Object.entries(f.ints)) gl.uniform1i(U(prog, u), v);
    gl.activeTexture(gl.TEXTURE0);
  }
}

const evalRes = { fbo: null, target: null, wi: null, wo: null, w: 0, h: 0 };

/** brdf() of `name` for N direction pairs (flat Float32Array 3N each) -> Float32Array(3N),
 * never NaN, Inf or negative. */
export function evaluateGPU(name, params, wi, wo) {
  if (!store.get("status").floatTargets) throw new Error("this WebGL 2 lacks EXT_color_buffer_float (float render targets)");
  const prog = getProgram(sourceKey(name), "eval");
  const n = wi.length / 3;
  if (wo.length !== wi.length) throw new Error("wi and wo must have the same length");
  const w = Math.max(1, Math.min(n, 1024)), h = Math.max(1, Math.ceil(n / w));
  const a = new Float32Array(w * h * 4), b = new Float32Array(w * h * 4);
  for (let k = 0; k < n; k++) {
    a[4 * k] = wi[3 * k]; a[4 * k + 1] = wi[3 * k + 1]; a[4 * k + 2] = wi[3 * k + 2];
    b[4 * k] = wo[3 * k]; b[4 * k + 1] = wo[3 * k + 1]; b[4 * k + 2] = wo[3 * k + 2];
  }
  for (const t of [evalRes.wi, evalRes.wo]) if (t) gl.deleteTexture(t);
  evalRes.wi = makeFloatTexture(w, h, a);
  evalRes.wo = makeFloatTexture(w, h, b);
  if (evalRes.w !== w || evalRes.h !== h) {
    if (evalRes.target) gl.deleteTexture(evalRes.target);
    if (!evalRes.fbo) evalRes.fbo = gl.createFramebuffer();
    evalRes.target = makeFloatTexture(w, h, null);
    gl.bindFramebuffer(gl.FRAMEBUFFER, evalRes.fbo);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, evalRes.target, 0);
    evalRes.w = w; evalRes.h = h;
  }
  gl.bindFramebuffer(gl.FRAMEBUFFER, evalRes.fbo);
  if (gl.checkFramebufferStatus(gl.FRAMEBUFFER) !== gl.FRAMEBUFFER_COMPLETE) {
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    throw new Error("float render target incomplete");
  }
  gl.viewport(0, 0, w, h);
  gl.disable(gl.BLEND);
  gl.disable(gl.DEPTH_TEST);
  gl.useProgram(prog);
  gl.activeTexture(gl.TEXTURE0); gl.bindTexture(gl.TEXTURE_2D, evalRes.wi);
  gl.activeTexture(gl.TEXTURE1); gl.bindTexture(gl.TEXTURE_2D, evalRes.wo);
  gl.uniform1i(U(prog, "bkw_wi"), 0);
  gl.uniform1i(U(prog, "bkw_wo"), 1);
  gl.activeTexture(gl.TEXTURE0);
  bindMaterial(prog, name, params);
  gl.drawArrays(gl.TRIANGLES, 0, 3);
  const out = new Float32Array(w * h * 4);
  gl.readPixels(0, 0, w, h, gl.RGBA, gl.FLOAT, out);
  gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  const res = new Float32Array(3 * n);
  for (let k = 0; k < n; k++) {
    for (let c = 0; c < 3; c++) {
      const v = out[4 * k + c];
      res[3 * k + c] = isFinite(v) && v > 0 ? v : 0; // never NaN, Inf or negative on the page
    }
  }
  return res;
}

/** The same through the server's numpy (/api/eval), for the cross-check. */
export async function evaluateNumpy(name, params, wi, wo) {
  const q = new URLSearchParams({ model: name, params: JSON.stringify(params || {}),
    wi: JSON.stringify(wi), wo: JSON.stringify(wo) });
  const r = await fetch("/api/eval?" + q.toString());
  const body = await r.json();
  if (!r.ok) throw new Error(body.error || r.statusText);
  return Float32Array.from(body.value.flat());
}

/** Fetch what a BRDF needs before it is drawn (a measured material's shader and network). */
export async function ensureLoaded(name) {
  const k = kindOf(name);
  if (k === null) throw new Error(`unknown BRDF '${name}': not a model, a built-in measured material or a loaded file`);
  if (k === "nbrdf") {
    const sources = store.get("sources");
    if (sources.__nbrdf === undefined) sources.__nbrdf = await fetchText("/api/nbrdf/shader");
    if (!nbrdfWeights[name]) {
      const body = await fetchJSON("/api/nbrdf?name=" + encodeURIComponent(name));
      nbrdfWeights[name] = Float32Array.from(body.weights);
    }
  }
}

/** The parameters of one BRDF checked by the server's own validation (params.py via /api/validate). */
export async function validated(model, params) {
  if (typeof model !== "string" || !model) throw new Error("a BRDF entry needs a 'model' name");
  if (params === null || typeof params !== "object" || Array.isArray(params)) throw new Error(`${model}: params must be a JSON object`);
  await ensureLoaded(model);
  if (kindOf(model) === "analytic") {
    const q = new URLSearchParams({ model, params: JSON.stringify(params) });
    const b = await fetchJSON("/api/validate?" + q.toString());
    if (!b.ok) throw new Error(b.error);
  } else if (kindOf(model) !== "brdf" && Object.keys(params).length) {
    throw new Error(`${model}: a measured material has no parameters, got ${Object.keys(params).join(", ")}`);
  }
  return params;
}
