// brdfkit explorer: plain JavaScript + WebGL 2, no build step, nothing fetched from outside.
//
// Every BRDF is evaluated in one WebGL 2 context by its own GLSL file (the renderer's
// shaders, served by /api/shader/<model>; measured materials by render/shaders/nbrdf.glsl
// (Neural-BRDF networks) or measured.glsl (a MERL table in a 3D texture)), appended with
// a small main per use:
//   * EVAL: brdf() for direction pairs read from float textures into an RGBA32F target,
//     read back (every plot, the albedo quadrature, window.brdfkit.eval);
//   * SPHERE: a lit sphere, ray-cast per pixel; SLICE: the θh × θd image;
//   * the lit object: the renderer's own pipeline (pipeline_lights/vertex/fragment.glsl,
//     pipeline_brdf.glsl or opengl_fixed.glsl) assembled as brdfkit.render.renderer does.
// The GL canvas is off-screen; each view is a 2D canvas the GL image is copied into.
// window.brdfkitStatus reports readiness and per-model compile errors.
"use strict";

(function () {
  const status = {
    ready: false, webgl2: false, floatTargets: false, renderer: null,
    models: {}, error: null, frames: 0,
    drawn: {},  // view -> how many times it was drawn (a setting redraws only the views it changes)
  };
  window.brdfkitStatus = status;

  const $ = (sel, root) => (root || document).querySelector(sel);
  const $$ = (sel, root) => Array.from((root || document).querySelectorAll(sel));
  const el = (tag, attrs, ...kids) => {
    const e = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) {
      if (k === "class") e.className = v;
      else if (k === "text") e.textContent = v;
      else e.setAttribute(k, v);
    }
    for (const k of kids) e.append(k);
    return e;
  };
  const DEG = Math.PI / 180;

  function setStatus(text, isError) {
    const s = $("#status");
    s.textContent = text;
    s.classList.toggle("error", !!isError);
  }

  // errors shown on the page (bad URL values, bad files, failed uploads): never silent
  const errorList = [];
  function showError(msg) {
    const text = String(msg && msg.message || msg).split("\n")[0];
    errorList.push(text);
    const box = $("#errors");
    const row = el("div", { class: "error-row" }, el("span", { text }));
    const x = el("button", { type: "button", title: "dismiss", text: "×" });
    x.addEventListener("click", () => row.remove());
    row.append(x);
    box.append(row);
  }
  function clearErrors() { $("#errors").textContent = ""; }

  // ------------------------------------------------------------------------
  // numbers
  // ------------------------------------------------------------------------
  const fmt = (x) => {
    if (x === null || x === undefined || !isFinite(x)) return String(x);
    const a = Math.abs(x);
    if (a !== 0 && (a < 1e-3 || a >= 1e5)) return x.toExponential(3);
    return String(+x.toPrecision(4));
  };
  // IEC 61966-2-1 sRGB transfer functions (Python twin: brdfkit.render.image.srgb_encode).
  const srgbToLinear = (c) => (c <= 0.04045 ? c / 12.92 : Math.pow((c + 0.055) / 1.055, 2.4));
  const srgbEncode = (c) => (c <= 0.0031308 ? 12.92 * c : 1.055 * Math.pow(c, 1 / 2.4) - 0.055);
  const linearToSrgb = (c) => (c <= 0.0031308 ? 12.92 * c : 1.055 * Math.pow(c, 1 / 2.4) - 0.055);
  const sph = (t, p) => [Math.sin(t) * Math.cos(p), Math.sin(t) * Math.sin(p), Math.cos(t)];

  // A slider position t in [0, 1] <-> a parameter value, linear or logarithmic,
  // respecting open bounds; the end points map exactly to closed bounds.
  function sliderMap(p) {
    let lo = p.min === null || p.min === undefined ? 0 : p.min;
    let hi = p.max;
    if (hi === null || hi === undefined) {
      const d = Array.isArray(p.default) ? Math.max(...p.default) : p.default;
      hi = Math.max(lo + 1, (d || 1) * 100);
    }
    const eps = (hi - lo) * 1e-3;
    const loEff = p.open_lo ? lo + eps : lo;
    const hiEff = p.open_hi ? hi - eps : hi;
    if (p.log_scale && hiEff > 0) {
      const a = loEff > 0 ? loEff : Math.max(hiEff * 1e-5, 1e-6);
      const la = Math.log(a), lb = Math.log(hiEff);
      return {
        lo, hi,
        toValue: (t) => (t <= 0 ? loEff : t >= 1 ? hiEff : Math.exp(la + t * (lb - la))),
        toSlider: (v) => (v <= a ? 0 : Math.min(1, (Math.log(v) - la) / (lb - la))),
        clamp: (v) => Math.min(hiEff, Math.max(loEff, v)),
      };
    }
    return {
      lo, hi,
      toValue: (t) => loEff + t * (hiEff - loEff),
      toSlider: (v) => Math.min(1, Math.max(0, (v - loEff) / (hiEff - loEff))),
      clamp: (v) => Math.min(hiEff, Math.max(loEff, v)),
    };
  }
  const STEPS = 1000;
  const BACKGROUND = 0.06; // linear grey behind the spheres
  const COLORS = ["#d9480f", "#1c7ed6", "#2b8a3e", "#ae3ec9", "#f08c00", "#0c8599", "#c2255c", "#5c940d"];

  // ------------------------------------------------------------------------
  // GLSL mains appended to a model's source (which defines brdf(wi, wo))
  // ------------------------------------------------------------------------
  const VERT = `#version 300 es
void main() {
    vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
`;
  const SRGB_GLSL = `
vec3 bkw_srgb(vec3 c) {  // one vector pow, not three scalar ones
    c = clamp(c, 0.0, 1.0);
    return mix(1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, 12.92 * c, lessThanEqual(c, vec3(0.0031308)));
}
`;
  const SPHERE_MAIN = `
uniform vec4 bkw_viewport;     // x, y, w, h in pixels
uniform vec3 bkw_light;        // unit, view space (viewer along +z)
uniform float bkw_scale;       // light irradiance x 2^exposure
uniform int bkw_tangent;       // 0: tangents along latitudes, 1: along longitudes
uniform vec3 bkw_background;  // sRGB-encoded (srgbEncode on the page)
out vec4 bkw_color;
${SRGB_GLSL}
void main() {
    vec2 p = ((gl_FragCoord.xy - bkw_viewport.xy) / bkw_viewport.zw * 2.0 - 1.0) * 1.06;
    float r2 = dot(p, p);
    if (r2 >= 1.0) { bkw_color = vec4(bkw_background, 1.0); return; }
    vec3 n = vec3(p, sqrt(1.0 - r2));
    vec3 axis = bkw_tangent == 0 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
    vec3 t = cross(axis, n);
    float tl = length(t);
    t = tl > 1e-6 ? t / tl : vec3(1.0, 0.0, 0.0);
    if (bkw_tangent == 1) t = -t;
    vec3 b = cross(n, t);
    vec3 L = bkw_light;
    vec3 V = vec3(0.0, 0.0, 1.0);
    vec3 wi = normalize(vec3(dot(L, t), dot(L, b), dot(L, n)));
    vec3 wo = normalize(vec3(dot(V, t), dot(V, b), dot(V, n)));
    vec3 c = brdf(wi, wo) * max(wi.z, 0.0) * bkw_scale;
    float r = sqrt(r2);
    float a = clamp((1.0 - r) / max(fwidth(r), 1e-6), 0.0, 1.0);
    bkw_color = vec4(mix(bkw_background, bkw_srgb(c), a), 1.0);
}
`;
  // θh × θd image at φd (Rusinkiewicz 1998, φh = 0): h = (sin θh, 0, cos θh); d in h's frame
  const SLICE_MAIN = `
uniform vec4 bkw_viewport;
uniform float bkw_phi_d;
uniform float bkw_scale;       // 2^exposure (linear) or the plot's maximum (log)
uniform int bkw_log;
uniform int bkw_channel;       // 0 rgb, 1 r, 2 g, 3 b, 4 luminance
uniform int bkw_ndotl;
out vec4 bkw_color;
${SRGB_GLSL}
void main() {
    vec2 uv = (gl_FragCoord.xy - bkw_viewport.xy) / bkw_viewport.zw;
    float th = uv.x * BK_HALF_PI, td = uv.y * BK_HALF_PI;
    vec3 h = vec3(sin(th), 0.0, cos(th));
    vec3 bx = vec3(cos(th), 0.0, -sin(th));
    vec3 d = vec3(sin(td) * cos(bkw_phi_d), sin(td) * sin(bkw_phi_d), cos(td));
    vec3 wi = normalize(d.x * bx + vec3(0.0, d.y, 0.0) + d.z * h);
    vec3 wo = normalize(2.0 * dot(h, wi) * h - wi);
    vec3 f = brdf(wi, wo);
    if (bkw_ndotl == 1) f *= max(wi.z, 0.0);
    if (bkw_channel == 1) f = vec3(f.r);
    else if (bkw_channel == 2) f = vec3(f.g);
    else if (bkw_channel == 3) f = vec3(f.b);
    else if (bkw_channel == 4) f = vec3(dot(f, vec3(0.2126, 0.7152, 0.0722)));
    vec3 c;
    if (bkw_log == 1) c = clamp(1.0 + log(max(f, vec3(1e-30)) / bkw_scale) / log(10.0) / 4.0, 0.0, 1.0);
    else c = f * bkw_scale;
    bkw_color = vec4(bkw_srgb(c), 1.0);
}
`;
  const EVAL_MAIN = `
uniform highp sampler2D bkw_wi;
uniform highp sampler2D bkw_wo;
out vec4 bkw_value;
void main() {
    ivec2 ij = ivec2(gl_FragCoord.xy);
    vec3 wi = texelFetch(bkw_wi, ij, 0).xyz;
    vec3 wo = texelFetch(bkw_wo, ij, 0).xyz;
    bkw_value = vec4(brdf(wi, wo), 1.0);
}
`;

  let gl = null;
  let glCanvas = null;
  let modelInfo = {};          // analytic models: name -> /api/models row
  let measuredNames = [];      // built-in measured materials
  const sources = {};          // source key -> GLSL text
  const programs = {};         // source key + "|" + kind -> WebGLProgram (or {error})
  const nbrdfWeights = {};     // material -> Float32Array(844): u_nbrdf[211] of nbrdf.glsl
  const merlTables = {};       // loaded MERL file label -> {texture}
  const brdfFiles = {};        // loaded .brdf label -> {info, source key}
  let shaderFiles = {};        // pipeline_*.glsl etc.
  let openglTable = null;

  function compileProgram(vertSource, fragSource) {
    const mk = (type, src) => {
      const s = gl.createShader(type);
      gl.shaderSource(s, src);
      gl.compileShader(s);
      if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) {
        const log = gl.getShaderInfoLog(s) || "compile failed";
        gl.deleteShader(s);
        throw new Error((type === gl.VERTEX_SHADER ? "vertex: " : "fragment: ") + log.trim());
      }
      return s;
    };
    const vs = mk(gl.VERTEX_SHADER, vertSource);
    const fs = mk(gl.FRAGMENT_SHADER, fragSource);
    const prog = gl.createProgram();
    gl.attachShader(prog, vs);
    gl.attachShader(prog, fs);
    gl.linkProgram(prog);
    gl.deleteShader(vs);
    gl.deleteShader(fs);
    if (!gl.getProgramParameter(prog, gl.LINK_STATUS)) {
      const log = gl.getProgramInfoLog(prog) || "link failed";
      throw new Error("link: " + log.trim());
    }
    prog._u = {};
    return prog;
  }
  const U = (prog, name) => {
    if (!(name in prog._u)) prog._u[name] = gl.getUniformLocation(prog, name);
    return prog._u[name];
  };

  // which GLSL source a BRDF name uses
  function kindOf(name) {
    if (modelInfo[name]) return "analytic";
    if (merlTables[name]) return "merl";
    if (brdfFiles[name]) return "brdf";
    if (measuredNames.includes(name)) return "nbrdf";
    return null;
  }
  function sourceKey(name) {
    const k = kindOf(name);
    if (k === "analytic") return name;
    if (k === "nbrdf") return "__nbrdf";
    if (k === "merl") return "__merl";
    if (k === "brdf") return brdfFiles[name].key;
    throw new Error(`unknown BRDF '${name}'`);
  }
  function infoOf(name) {
    const k = kindOf(name);
    if (k === "analytic") return modelInfo[name];
    if (k === "brdf") return brdfFiles[name].info;
    return { name, title: k === "merl" ? "MERL table (dropped file), nearest bin" : "measured material (Neural-BRDF network)",
      reference: "", params: [] };
  }

  // The per-pixel views compile a model once per combination of its integer parameters
  // (choices, booleans): their `uniform int u_x;` becomes `const int u_x = v;`, the rest of
  // the model's GLSL unchanged, so the compiler drops the branches not taken. A software
  // renderer (SwiftShader) otherwise runs every side of a branch on a uniform, tables of
  // unused options included (microfacet's sphere at 750x750: 4.6 s -> 0.11 s a frame).
  function intConstants(name, params) {
    const k = kindOf(name);
    if (k !== "analytic" && k !== "brdf") return null;
    const info = infoOf(name);
    const eff = effectiveParams(info, params);
    const out = {};
    for (const p of info.params) {
      if (!p.uniform || p.uniform.type !== "int") continue;
      const v = eff[p.name];
      out[p.uniform.name] = p.kind === "choice" ? Math.max(0, p.choices.indexOf(v))
        : p.kind === "bool" ? (v === true || v === 1 || v === "true" ? 1 : 0) : Math.round(+v);
    }
    return Object.keys(out).length ? out : null;
  }
  function sourceOf(key, consts) {
    let src = sources[key];
    if (src === undefined) throw new Error(`no GLSL source for '${key}'`);
    for (const [n, v] of Object.entries(consts || {})) {
      const re = new RegExp(`^uniform int ${n};`, "m");
      src = src.replace(re, `const int ${n} = ${v};`);  // (a source without the line keeps its uniform)
    }
    return src;
  }

  // "eval" | "sphere" | "slice" | "obj-flat" | "obj-gouraud" | "obj-phong" | "gl-flat" ...;
  // consts: intConstants(...) or null
  function getProgram(key, kind, consts) {
    const id = key + "|" + kind + (consts ? "|" + JSON.stringify(consts) : "");
    if (programs[id]) {
      if (programs[id].error) throw new Error(programs[id].error);
      return programs[id];
    }
    try {
      let prog;
      if (kind === "eval" || kind === "sphere" || kind === "slice") {
        const src = sourceOf(key, consts);
        const main = kind === "eval" ? EVAL_MAIN : kind === "sphere" ? SPHERE_MAIN : SLICE_MAIN;
        prog = compileProgram(VERT, src + main);
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

  // The renderer's pipeline, assembled as brdfkit.render.renderer.Renderer._program does
  // (GLSL ES 3.00 instead of 3.30): kind = "obj-<shading>" (a BRDF) or "gl-<shading>" (fixed function).
  function pipelineProgram(key, kind, consts) {
    const [what, shading] = kind.split("-");
    const F = shaderFiles;
    for (const f of ["pipeline_lights.glsl", "pipeline_vertex.glsl", "pipeline_fragment.glsl", "pipeline_brdf.glsl", "opengl_fixed.glsl"]) {
      if (F[f] === undefined) throw new Error(`shader file ${f} not loaded`);
    }
    const where = what === "ibl" ? "ibl" : shading === "phong" ? "fragment" : "vertex";
    const defines = [];
    if (shading === "flat") defines.push("#define BKR_FLAT");
    defines.push({ vertex: "#define BKR_LIGHT_IN_VERTEX", fragment: "#define BKR_LIGHT_IN_FRAGMENT", ibl: "#define BKR_IBL" }[where]);
    // GLSL ES fragment shaders have no default float precision: declare it first (and
    // highp samplers: the environment and the MERL table are float textures)
    const head = "#version 300 es\n" + defines.join("\n")
      + "\nprecision highp float;\nprecision highp int;\nprecision highp sampler2D;\nprecision highp sampler3D;\n";
    let body;
    if (what === "gl") body = F["pipeline_lights.glsl"] + F["opengl_fixed.glsl"];
    else {
      const src = sourceOf(key, consts);
      body = src.replace(/^#version[^\n]*\n/, "") + F["pipeline_lights.glsl"];
      if (what === "ibl") {
        if (F["ibl.glsl"] === undefined) throw new Error("this server has no image-based lighting shaders");
        body += F["ibl_sampling.glsl"] + F["ibl.glsl"];
      } else body += F["pipeline_brdf.glsl"];
    }
    const vs = head + (where === "vertex" ? body : F["pipeline_lights.glsl"]) + F["pipeline_vertex.glsl"];
    const fs = head + (where !== "vertex" ? body : "") + F["pipeline_fragment.glsl"];
    const prog = compileProgram(vs, fs);
    prog._attr = {
      position: gl.getAttribLocation(prog, "in_position"),
      normal: gl.getAttribLocation(prog, "in_normal"),
      tangent: gl.getAttribLocation(prog, "in_tangent"),
    };
    return prog;
  }

  // the uniform values of a parameter set (a plain object, as for /api/eval)
  function setModelUniforms(prog, info, values) {
    for (const p of info.params) {
      const loc = U(prog, p.uniform.name);
      let v = values[p.name];
      if (loc === null || v === null || v === undefined) continue;
      if (p.kind === "scalar") gl.uniform1f(loc, +v);
      else if (p.kind === "rgb") {
        if (!Array.isArray(v)) v = [v, v, v];
        gl.uniform3f(loc, +v[0], +v[1], +v[2]);
      } else if (p.kind === "bool") gl.uniform1i(loc, v === true || v === 1 || v === "true" ? 1 : 0);
      else if (p.kind === "choice") gl.uniform1i(loc, Math.max(0, p.choices.indexOf(v)));
      else gl.uniform1i(loc, Math.round(+v));
    }
  }

  // bind what a BRDF needs: its parameters, its network weights or its table
  function bindMaterial(prog, name, params) {
    const k = kindOf(name);
    if (k === "analytic" || k === "brdf") {
      const info = infoOf(name);
      const eff = effectiveParams(info, params);
      setModelUniforms(prog, info, eff);
    } else if (k === "nbrdf") {
      const w = nbrdfWeights[name];
      if (!w) throw new Error(`measured material '${name}' is not loaded yet`);
      gl.uniform4fv(U(prog, "u_nbrdf[0]") || U(prog, "u_nbrdf"), w);
    } else if (k === "merl") {
      gl.activeTexture(gl.TEXTURE3);
      gl.bindTexture(gl.TEXTURE_3D, merlTables[name].texture);
      gl.uniform1i(U(prog, "u_table"), 3);
      gl.uniform1i(U(prog, "u_interpolation"), 0);
      gl.activeTexture(gl.TEXTURE0);
    }
  }

  // defaults filled in, the microfacet-style alpha / alpha_x / alpha_y rule applied
  function effectiveParams(info, given) {
    const v = {};
    for (const p of info.params) v[p.name] = p.default;
    for (const [k, x] of Object.entries(given || {})) {
      if (!(k in v)) throw new Error(`${info.name}: unknown parameter '${k}'`);
      v[k] = x;
    }
    if ("alpha" in v && "alpha_x" in v && "alpha_y" in v) {
      if (given && given.alpha !== undefined && given.alpha !== null) {
        v.alpha_x = v.alpha_y = given.alpha;
      } else {
        v.alpha = v.alpha_x === v.alpha_y ? v.alpha_x : null;
      }
    }
    return v;
  }

  // ------------------------------------------------------------------------
  // evaluation on the GPU: brdf() for N direction pairs (flat Float32Array 3N) -> Float32Array(3N)
  // ------------------------------------------------------------------------
  const evalRes = { fbo: null, target: null, wi: null, wo: null, w: 0, h: 0 };

  function makeFloatTexture(w, h, data) {
    const tex = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, tex);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, w, h, 0, gl.RGBA, gl.FLOAT, data);
    return tex;
  }

  function evaluateGPU(name, params, wi, wo) {
    if (!status.floatTargets) throw new Error("this WebGL 2 lacks EXT_color_buffer_float (float render targets)");
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

  const flat3 = (list) => {
    const a = new Float32Array(3 * list.length);
    list.forEach((v, k) => { a[3 * k] = v[0]; a[3 * k + 1] = v[1]; a[3 * k + 2] = v[2]; });
    return a;
  };

  // the same through the server's numpy (/api/eval), for the cross-check
  async function evaluateNumpy(name, params, wi, wo) {
    const q = new URLSearchParams({ model: name, params: JSON.stringify(params || {}),
      wi: JSON.stringify(wi), wo: JSON.stringify(wo) });
    const r = await fetch("/api/eval?" + q.toString());
    const body = await r.json();
    if (!r.ok) throw new Error(body.error || r.statusText);
    return Float32Array.from(body.value.flat());
  }

  // ------------------------------------------------------------------------
  // loading BRDF sources, measured materials, files
  // ------------------------------------------------------------------------
  async function fetchText(url) {
    const r = await fetch(url);
    const t = await r.text();
    if (!r.ok) { let m = t; try { m = JSON.parse(t).error; } catch (e) { /* plain text */ } throw new Error(m); }
    return t;
  }
  async function fetchJSON(url, opts) {
    const r = await fetch(url, opts);
    const t = await r.text();
    let body;
    try { body = JSON.parse(t); } catch (e) { throw new Error(`${url}: not JSON (${r.status})`); }
    if (!r.ok) throw new Error(body.error || r.statusText);
    return body;
  }

  async function ensureLoaded(name) {
    const k = kindOf(name);
    if (k === null) throw new Error(`unknown BRDF '${name}': not a model, a built-in measured material or a loaded file`);
    if (k === "nbrdf") {
      if (sources.__nbrdf === undefined) sources.__nbrdf = await fetchText("/api/nbrdf/shader");
      if (!nbrdfWeights[name]) {
        const body = await fetchJSON("/api/nbrdf?name=" + encodeURIComponent(name));
        nbrdfWeights[name] = Float32Array.from(body.weights);
      }
    }
  }

  async function loadMerlFile(file) {
    const buf = await file.arrayBuffer();
    const r = await fetch("/api/merl", { method: "POST", body: buf, headers: { "Content-Type": "application/octet-stream" } });
    if (!r.ok) { const b = await r.json().catch(() => ({ error: r.statusText })); throw new Error(`${file.name}: ${b.error}`); }
    const texels = new Float32Array(await r.arrayBuffer());
    if (texels.length !== 90 * 90 * 180 * 4) throw new Error(`${file.name}: unexpected table size from the server`);
    if (sources.__merl === undefined) sources.__merl = await fetchText("/api/measured/shader");
    const tex = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_3D, tex);
    for (const p of [gl.TEXTURE_MIN_FILTER, gl.TEXTURE_MAG_FILTER]) gl.texParameteri(gl.TEXTURE_3D, p, gl.NEAREST);
    for (const p of [gl.TEXTURE_WRAP_S, gl.TEXTURE_WRAP_T, gl.TEXTURE_WRAP_R]) gl.texParameteri(gl.TEXTURE_3D, p, gl.CLAMP_TO_EDGE);
    gl.texImage3D(gl.TEXTURE_3D, 0, gl.RGBA32F, 180, 90, 90, 0, gl.RGBA, gl.FLOAT, texels);
    const label = "file:" + file.name.replace(/\.(binary|bin)$/, "");
    if (merlTables[label]) gl.deleteTexture(merlTables[label].texture);
    merlTables[label] = { texture: tex };
    refreshModelSelects();
    return label;
  }

  async function loadBrdfFile(file) {
    const text = await file.text();
    const r = await fetch("/api/brdf?name=" + encodeURIComponent(file.name), { method: "POST", body: text, headers: { "Content-Type": "text/plain" } });
    const body = await r.json().catch(() => ({ error: r.statusText }));
    if (!r.ok) throw new Error(`${file.name}: ${r.status === 404 ? "loading .brdf files is not available in this build" : body.error}`);
    const label = "brdf:" + file.name.replace(/\.brdf$/, "");
    const key = "__brdf:" + label;
    sources[key] = body.glsl;
    for (const k of Object.keys(programs)) if (k.startsWith(key + "|")) delete programs[k]; // a file loaded again
    brdfFiles[label] = { info: Object.assign({ title: "Disney BRDF Explorer file", reference: "" }, body.info, { name: label }), key };
    refreshModelSelects();
    return label;
  }

  async function loadObjFile(file) {
    const m = await fetchJSON("/api/mesh", { method: "POST", body: await file.arrayBuffer() });
    m.name = file.name;
    uploadedMesh = meshBuffers(m);
    $("#obj-mesh option[value=uploaded]").disabled = false;
    return "obj";
  }

  // Dropped files survive a reload: their bytes are kept in IndexedDB under their SHA-256,
  // the state (URL, saved view) names them ({name, sha256}); a state naming a file this
  // browser no longer holds is an error on the page.
  const FILE_KINDS = [[/\.(binary|bin)$/i, loadMerlFile], [/\.brdf$/i, loadBrdfFile], [/\.obj$/i, loadObjFile]];
  const loadedFiles = {};  // what a file made (file:NAME, brdf:NAME, or "obj") -> {name, sha256}
  const fileLoader = (name) => (FILE_KINDS.find(([re]) => re.test(name)) || [null, null])[1];
  let idbOpen = null;
  function idbStore(mode) {
    if (!idbOpen) {
      idbOpen = new Promise((resolve, reject) => {
        if (!window.indexedDB) { reject(new Error("this browser has no IndexedDB")); return; }
        const r = indexedDB.open("brdfkit-files", 1);
        r.onupgradeneeded = () => r.result.createObjectStore("files");
        r.onsuccess = () => resolve(r.result);
        r.onerror = () => reject(new Error("IndexedDB: " + (r.error ? r.error.message : "cannot open")));
      });
      idbOpen.catch(() => { idbOpen = null; });
    }
    return idbOpen.then((db) => db.transaction("files", mode).objectStore("files"));
  }
  const idbRequest = (req) => new Promise((resolve, reject) => {
    req.onsuccess = () => resolve(req.result);
    req.onerror = () => reject(new Error("IndexedDB: " + (req.error ? req.error.message : "failed")));
  });
  async function sha256Hex(bytes) {
    if (!(window.crypto && crypto.subtle)) throw new Error("no crypto.subtle (the page is not a secure context: open it as 127.0.0.1 or localhost)");
    const d = new Uint8Array(await crypto.subtle.digest("SHA-256", bytes));
    return Array.from(d, (b) => b.toString(16).padStart(2, "0")).join("");
  }
  // load a dropped file's bytes into the page and keep them; -> the label of what it made
  async function loadAndKeep(name, bytes) {
    const label = await fileLoader(name)(new File([bytes], name));
    try {
      const sha256 = await sha256Hex(bytes);
      await idbRequest((await idbStore("readwrite")).put({ name, bytes }, sha256));
      loadedFiles[label] = { name, sha256 };
    } catch (e) {
      delete loadedFiles[label];
      showError(`${name}: loaded, but not kept for a reload (${e.message})`);
    }
    return label;
  }
  // the files a state names, back from IndexedDB (a missing one: an error on the page)
  async function restoreFiles(files, origin) {
    if (!Array.isArray(files)) { showError(`${origin}: files must be a list of {"name", "sha256"}`); return; }
    for (const f of files) {
      const ok = f && typeof f.name === "string" && typeof f.sha256 === "string" && /^[0-9a-f]{64}$/.test(f.sha256);
      if (!ok || !fileLoader(f.name)) { showError(`${origin}: bad files entry ${JSON.stringify(f)}`); continue; }
      if (Object.values(loadedFiles).some((g) => g.sha256 === f.sha256 && g.name === f.name)) continue;
      try {
        const rec = await idbRequest((await idbStore("readonly")).get(f.sha256));
        if (!rec) throw new Error("it is not stored in this browser (IndexedDB was cleared, or another browser or profile): drop the file again");
        const label = await fileLoader(f.name)(new File([rec.bytes], f.name));
        loadedFiles[label] = { name: f.name, sha256: f.sha256 };
      } catch (e) { showError(`${origin}: dropped file '${f.name}' (sha256 ${f.sha256.slice(0, 12)}…): ${e.message}`); }
    }
  }
  // the kept files the current state uses
  function stateFiles(models) {
    return Object.entries(loadedFiles)
      .filter(([label]) => (label === "obj" ? getSetting("obj-mesh") === "uploaded" : models.includes(label)))
      .map(([, f]) => ({ name: f.name, sha256: f.sha256 }));
  }

  // ------------------------------------------------------------------------
  // the BRDF panels
  // ------------------------------------------------------------------------
  const panels = [];
  let nextPanelId = 0;

  function modelOptions(select, current) {
    select.textContent = "";
    const g1 = el("optgroup", { label: "analytic models" });
    for (const name of Object.keys(modelInfo)) {
      const st = status.models[name];
      g1.append(el("option", { value: name, text: name + (st && !st.ok ? " (shader error)" : "") }));
    }
    select.append(g1);
    const loaded = Object.keys(merlTables).concat(Object.keys(brdfFiles));
    if (loaded.length) {
      const g = el("optgroup", { label: "loaded files" });
      for (const n of loaded) g.append(el("option", { value: n, text: n }));
      select.append(g);
    }
    const g2 = el("optgroup", { label: `measured (${measuredNames.length})` });
    for (const n of measuredNames) g2.append(el("option", { value: n, text: n }));
    select.append(g2);
    if (current) select.value = current;
  }
  function refreshModelSelects() { for (const p of panels) modelOptions(p.select, p.model); refreshObjectMaterials(); }

  class Panel {
    constructor(color) {
      this.id = nextPanelId++;
      this.color = color;
      this.visible = true;
      this.model = null;
      this.values = {};
      this.controls = {};
      this.root = el("div", { class: "panel", "data-panel": String(this.id) });
      this.root.style.setProperty("--c", color);
      this.select = el("select", { class: "model-select", title: "the BRDF of this panel" });
      this.visibleBox = el("input", { type: "checkbox", class: "visible", title: "visible" });
      this.visibleBox.checked = true;
      const solo = el("button", { type: "button", class: "solo", title: "show only this BRDF", text: "solo" });
      const remove = el("button", { type: "button", class: "remove", title: "remove this BRDF", text: "×" });
      const head = el("div", { class: "panel-head" }, el("span", { class: "swatch" }), this.select,
        el("label", { class: "vis", title: "visible" }, this.visibleBox, "show"), solo, remove);
      this.title = el("p", { class: "model-title" });
      this.paramsBox = el("div", { class: "params" });
      const reset = el("button", { type: "button", class: "reset", text: "reset to defaults" });
      this.root.append(head, this.title, this.paramsBox, reset);
      this.select.addEventListener("change", () => this.setModelAsync(this.select.value));
      this.visibleBox.addEventListener("change", () => { this.visible = this.visibleBox.checked; changed(); });
      solo.addEventListener("click", () => { for (const p of panels) p.setVisible(p === this); changed(); });
      remove.addEventListener("click", () => removePanel(this));
      reset.addEventListener("click", () => { this.setModel(this.model); changed(); });
    }

    setVisible(v) { this.visible = !!v; this.visibleBox.checked = this.visible; }

    async setModelAsync(name, params) {
      try {
        await ensureLoaded(name);
        this.setModel(name, params);
      } catch (e) { showError(e); this.select.value = this.model || ""; }
      changed();
    }

    // synchronous: the BRDF must be loaded (ensureLoaded)
    setModel(name, params) {
      this.model = name;
      this.paramsBox.textContent = "";
      this.controls = {};
      modelOptions(this.select, name);
      const info = infoOf(name);
      const st = status.models[name];
      this.title.textContent = info.title + (st && !st.ok ? "  [shader error: " + st.error + "]" : "");
      this.title.title = info.reference || "";
      this.values = effectiveParams(info, params || {});
      for (const p of info.params) this.paramsBox.append(this.makeControl(p));
      this.refreshAll();
    }

    makeControl(p) {
      const row = el("div", { class: "param", "data-param": p.name, title: `${p.doc || ""} — allowed ${p.range || ""}` });
      const label = el("span", { class: "name" }, p.name);
      if (p.unit) label.append(" ", el("small", { text: p.unit }));
      row.append(label);
      const c = { p, row };
      this.controls[p.name] = c;
      const onchange = () => { this.onChange(p.name); changed(); };
      if (p.kind === "choice") {
        const s = el("select", {});
        for (const ch of p.choices) s.append(el("option", { value: ch, text: ch }));
        s.addEventListener("change", () => { this.values[p.name] = s.value; onchange(); });
        c.select = s; row.append(s);
      } else if (p.kind === "bool") {
        const cb = el("input", { type: "checkbox" });
        cb.addEventListener("change", () => { this.values[p.name] = cb.checked; onchange(); });
        c.checkbox = cb; row.append(el("span", { class: "rgb" }, cb));
      } else if (p.kind === "scalar" || p.kind === "int") {
        const map = sliderMap(p);
        const slider = el("input", { type: "range", min: "0", max: String(STEPS), step: "1" });
        const num = el("input", { type: "number", step: "any" });
        slider.addEventListener("input", () => {
          let v = map.toValue(slider.value / STEPS);
          if (p.kind === "int") v = Math.round(v);
          this.values[p.name] = v; num.value = fmt(v); onchange();
        });
        num.addEventListener("change", () => {
          let v = parseFloat(num.value);
          if (!isFinite(v)) v = this.values[p.name] === null ? p.default : this.values[p.name];
          v = map.clamp(v);
          if (p.kind === "int") v = Math.round(v);
          this.values[p.name] = v; this.refresh(p.name); onchange();
        });
        Object.assign(c, { map, slider, num });
        row.append(slider, num);
        if (p.name === "alpha" && this.values.alpha_x !== undefined) {
          c.note = el("span", { class: "note" });
          row.append(el("span", {}), c.note);
        }
      } else { // rgb: one slider scales the triple (keeping its hue), plus r, g, b fields
        const map = sliderMap(p);
        const slider = el("input", { type: "range", min: "0", max: String(STEPS), step: "1" });
        const level = el("input", { type: "number", step: "any", title: "the largest channel" });
        const box = el("span", { class: "rgb triple" });
        const fields = [0, 1, 2].map((i) => el("input", { type: "number", step: "any", title: "rgb"[i] }));
        let picker = null;
        if (map.lo >= 0 && map.hi <= 1) {
          picker = el("input", { type: "color", title: "pick a colour (sRGB, converted to linear)" });
          picker.addEventListener("input", () => {
            const hex = picker.value;
            const lin = [1, 3, 5].map((i) => srgbToLinear(parseInt(hex.slice(i, i + 2), 16) / 255));
            this.values[p.name] = lin.map((x) => map.clamp(x));
            this.refresh(p.name, "picker"); onchange();
          });
          box.append(picker);
        }
        box.append(...fields);
        slider.addEventListener("input", () => {
          const target = map.toValue(slider.value / STEPS);
          this.values[p.name] = this.scaleTriple(p.name, target, map);
          this.refresh(p.name, "slider"); onchange();
        });
        level.addEventListener("change", () => {
          const target = parseFloat(level.value);
          if (isFinite(target)) this.values[p.name] = this.scaleTriple(p.name, map.clamp(target), map);
          this.refresh(p.name); onchange();
        });
        fields.forEach((f, i) => f.addEventListener("change", () => {
          const v = this.triple(p.name).slice();
          const x = parseFloat(f.value);
          if (isFinite(x)) v[i] = map.clamp(x);
          this.values[p.name] = v;
          this.refresh(p.name); onchange();
        }));
        Object.assign(c, { map, slider, level, fields, picker });
        row.append(slider, level, box);
      }
      return row;
    }

    triple(name) {
      const v = this.values[name];
      return Array.isArray(v) ? v.map(Number) : [+v, +v, +v];
    }

    scaleTriple(name, target, map) {
      const v = this.triple(name);
      const m = Math.max(...v);
      if (m <= 0) return [target, target, target];
      if (!this.hue || this.hue.name !== name || Math.abs(Math.max(...this.hue.v) - 1) > 1e-9) {
        this.hue = { name, v: v.map((x) => x / m) };
      }
      return this.hue.v.map((x) => map.clamp(x * target));
    }

    onChange(name) {
      const v = this.values;
      if (!("alpha" in v && "alpha_x" in v && "alpha_y" in v)) return;
      if (name === "alpha") { v.alpha_x = v.alpha_y = v.alpha; this.refresh("alpha_x"); this.refresh("alpha_y"); }
      else if (name === "alpha_x" || name === "alpha_y") { v.alpha = v.alpha_x === v.alpha_y ? v.alpha_x : null; this.refresh("alpha"); }
    }

    refreshAll() { for (const k of Object.keys(this.controls)) this.refresh(k); }

    refresh(name, source) {
      const c = this.controls[name];
      if (!c) return;
      const p = c.p, v = this.values[name];
      if (p.kind === "choice") c.select.value = v;
      else if (p.kind === "bool") c.checkbox.checked = !!v;
      else if (p.kind === "scalar" || p.kind === "int") {
        if (v === null) {
          c.num.value = ""; c.num.placeholder = "—";
          if (c.note) c.note.textContent = "anisotropic: alpha_x ≠ alpha_y (move alpha to make it isotropic)";
        } else {
          c.slider.value = String(Math.round(c.map.toSlider(v) * STEPS));
          c.num.value = fmt(v);
          if (c.note) c.note.textContent = "sets alpha_x = alpha_y";
        }
      } else {
        const t = this.triple(name);
        const m = Math.max(...t);
        if (source !== "slider") { c.slider.value = String(Math.round(c.map.toSlider(m) * STEPS)); this.hue = null; }
        c.level.value = fmt(m);
        t.forEach((x, i) => { c.fields[i].value = fmt(x); });
        if (c.picker && source !== "picker") {
          const norm = m > 0 ? t.map((x) => x / m) : [0, 0, 0];
          c.picker.value = "#" + norm.map((x) => Math.round(linearToSrgb(Math.min(1, Math.max(0, x))) * 255)
            .toString(16).padStart(2, "0")).join("");
        }
      }
    }

    // parameters as JSON for /api/eval and eval() (alpha left out when undefined or redundant)
    params() {
      const out = {};
      for (const [k, v] of Object.entries(this.values)) if (v !== null) out[k] = v;
      if ("alpha" in out && "alpha_x" in out) delete out.alpha;
      return out;
    }
  }

  function addPanel(name, params) {
    const used = new Set(panels.map((p) => p.color));
    const color = COLORS.find((c) => !used.has(c)) || COLORS[panels.length % COLORS.length];
    const p = new Panel(color);
    panels.push(p);
    $("#brdf-list").append(p.root);
    p.setModel(name, params);
    return p;
  }
  function removePanel(p) {
    if (panels.length <= 1) { showError("the last BRDF cannot be removed"); return; }
    panels.splice(panels.indexOf(p), 1);
    p.root.remove();
    changed();
  }
  const visiblePanels = () => panels.filter((p) => p.visible && p.model);

  // ------------------------------------------------------------------------
  // view settings (the global bar and each view's controls)
  // ------------------------------------------------------------------------
  const SETTINGS = {  // id -> kind
    "theta-i": "num", "phi-i": "num", "theta-h": "num", "theta-d": "num", "phi-d": "num", exposure: "num",
    channel: "str", scale: "str", ndotl: "bool",
    "light-theta": "num", "light-phi": "num", tangent: "str", "albedo-method": "str",
    "obj-mesh": "str", "obj-tess": "num", "obj-lighting": "str", "obj-ibl-spp": "num", "obj-shading": "str", "obj-material": "str", "obj-light-type": "str",
    "obj-light-theta": "num", "obj-light-phi": "num", "obj-light-dist": "num", "obj-light-diffuse": "num",
    "obj-light-specular": "num", "obj-light-ambient": "num", "obj-scene-ambient": "num",
    "obj-att-c": "num", "obj-att-l": "num", "obj-att-q": "num", "obj-local-viewer": "bool",
  };
  const DEFAULTS = {};
  const orbit = { lobe3d: { yaw: -60, pitch: 25, zoom: 1.3 }, object: { yaw: 20, pitch: 15, zoom: 1 } };
  const ORBIT_DEFAULTS = JSON.parse(JSON.stringify(orbit));

  function num(id) { return parseFloat($("#" + id).value); }
  function getSetting(id) {
    const e = $("#" + id), k = SETTINGS[id];
    return k === "bool" ? e.checked : k === "num" ? parseFloat(e.value) : e.value;
  }
  function setSetting(id, v) {
    const e = $("#" + id), k = SETTINGS[id];
    if (!e) throw new Error(`unknown view setting '${id}'`);
    if (k === "bool") {
      if (typeof v !== "boolean") throw new Error(`view setting '${id}' must be true or false, got ${JSON.stringify(v)}`);
      e.checked = v;
    } else if (k === "num") {
      if (typeof v !== "number" || !isFinite(v)) throw new Error(`view setting '${id}' must be a number, got ${JSON.stringify(v)}`);
      const lo = e.min === "" ? -Infinity : parseFloat(e.min), hi = e.max === "" ? Infinity : parseFloat(e.max);
      if (v < lo || v > hi) throw new Error(`view setting '${id}' = ${v} is out of range; allowed [${e.min}, ${e.max}]`);
      e.value = String(v);
    } else {
      const opts = e.tagName === "SELECT" ? Array.from(e.options).filter((o) => !o.disabled).map((o) => o.value) : null;
      if (opts && !opts.includes(v)) throw new Error(`view setting '${id}' = ${JSON.stringify(v)}; valid: ${opts.join(", ")}`);
      e.value = v;
    }
  }
  function updateOutputs() {
    for (const o of $$("output[for]")) {
      const id = o.getAttribute("for");
      const v = num(id);
      o.textContent = id === "exposure" ? v.toFixed(1) + " EV" : id === "obj-tess" || id === "obj-light-dist" ? fmt(v) : fmt(v) + "°";
    }
  }

  // ------------------------------------------------------------------------
  // state: the URL (?model=NAME&p=JSON&compare=JSON&view=JSON) and parameter files
  // ------------------------------------------------------------------------
  const VIEWS = ["lobe3d", "polar", "theta_h", "theta_d", "theta_v", "albedo", "sphere", "slice", "object"];
  const panes = ["polar", "sphere"];

  function getState() {
    const list = panels.filter((p) => p.model);
    const first = list[0];
    const view = {};
    for (const id of Object.keys(SETTINGS)) view[id] = getSetting(id);
    const st = {
      model: first ? first.model : null,
      params: first ? first.params() : {},
      visible: first ? first.visible : true,
      compare: list.slice(1).map((p) => ({ model: p.model, params: p.params(), visible: p.visible })),
      panes: panes.slice(),
      view,
      orbit: JSON.parse(JSON.stringify(orbit)),
    };
    const files = stateFiles(list.map((p) => p.model));
    if (files.length) st.files = files;
    return st;
  }

  function stateToURL(st) {
    const q = new URLSearchParams();
    q.set("model", st.model);
    q.set("p", JSON.stringify(st.params));
    if (st.visible === false) q.set("hide", "1");
    if (st.compare.length) q.set("compare", JSON.stringify(st.compare));
    if (st.files) q.set("files", JSON.stringify(st.files));
    const view = {};
    for (const [k, v] of Object.entries(st.view)) if (v !== DEFAULTS[k]) view[k] = v;
    view.panes = st.panes;
    view.orbit = st.orbit;
    q.set("view", JSON.stringify(view));
    return "?" + q.toString();
  }

  function parseJSONParam(text, what) {
    try { return JSON.parse(text); } catch (e) { throw new Error(`${what}: not valid JSON (${e.message})`); }
  }

  // URL query -> a state object (throws with a one-line message naming the bad part)
  function urlToState(search) {
    const q = new URLSearchParams(search);
    const allowed = new Set(["model", "p", "compare", "view", "hide", "files"]);
    for (const k of q.keys()) if (!allowed.has(k)) throw new Error(`URL: unknown parameter '${k}'; allowed: model, p, compare, view, files`);
    const st = { model: q.get("model"), params: {}, compare: [], view: {}, visible: q.get("hide") !== "1" };
    if (q.has("p")) st.params = parseJSONParam(q.get("p"), "URL p");
    if (q.has("files")) st.files = parseJSONParam(q.get("files"), "URL files");
    const c = q.get("compare");
    if (c) {
      if (c.trim().startsWith("[")) st.compare = parseJSONParam(c, "URL compare");
      else st.compare = c.split(",").filter((s) => s).map((m) => ({ model: m, params: {} }));
    }
    if (q.has("view")) {
      const v = parseJSONParam(q.get("view"), "URL view");
      if (v === null || typeof v !== "object" || Array.isArray(v)) throw new Error("URL view: must be a JSON object");
      if (v.panes) { st.panes = v.panes; delete v.panes; }
      if (v.orbit) { st.orbit = v.orbit; delete v.orbit; }
      st.view = v;
    }
    return st;
  }

  // the parameters of one BRDF checked by the server's own validation (params.py via /api/eval)
  async function validated(model, params) {
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

  // apply a state object; every bad part is reported on the page, the rest still applied
  async function applyState(st, origin) {
    if (st === null || typeof st !== "object" || Array.isArray(st)) throw new Error(`${origin}: expected a JSON object`);
    if (st.files !== undefined) await restoreFiles(st.files, origin);  // before the panels that use them
    const entries = [];
    if (st.model !== undefined && st.model !== null) entries.push({ model: st.model, params: st.params || {}, visible: st.visible !== false });
    if (st.compare !== undefined) {
      if (!Array.isArray(st.compare)) showError(`${origin}: compare must be a list of {"model", "params"}`);
      else for (const c of st.compare) {
        if (typeof c === "string") entries.push({ model: c, params: {}, visible: true });
        else if (c && typeof c === "object") entries.push({ model: c.model, params: c.params || {}, visible: c.visible !== false });
        else showError(`${origin}: bad compare entry ${JSON.stringify(c)}`);
      }
    }
    const good = [];
    for (const e of entries) {
      try {
        await validated(e.model, e.params);
        good.push(e);
      } catch (err) { showError(`${origin}: ${err.message}`); }
    }
    if (good.length) {
      for (const p of panels.slice()) { p.root.remove(); }
      panels.length = 0;
      for (const e of good) { const p = addPanel(e.model, e.params); p.setVisible(e.visible); }
    }
    const view = st.view === undefined ? {} : st.view;
    if (view === null || typeof view !== "object" || Array.isArray(view)) showError(`${origin}: view must be a JSON object`);
    else for (const [k, v] of Object.entries(DEFAULTS)) if (!(k in view)) setSetting(k, v);  // the state is the whole view
    for (const [k, v] of Object.entries(view || {})) {
      try { setSetting(k, v); } catch (err) { showError(`${origin}: ${err.message}`); }
    }
    if (st.panes !== undefined) {
      if (!Array.isArray(st.panes) || st.panes.length !== 2 || st.panes.some((v) => !VIEWS.includes(v))) {
        showError(`${origin}: panes must be two of ${VIEWS.join(", ")}`);
      } else { showView(st.panes[0], 0); showView(st.panes[1], 1); }
    }
    if (st.orbit && typeof st.orbit === "object") {
      for (const k of ["lobe3d", "object"]) {
        const o = st.orbit[k];
        if (!o) continue;
        for (const f of ["yaw", "pitch", "zoom"]) if (typeof o[f] === "number" && isFinite(o[f])) orbit[k][f] = o[f];
      }
    }
    changed();
  }

  let urlTimer = null;
  function updateURL() {
    if (urlTimer) return;
    urlTimer = setTimeout(() => {
      urlTimer = null;
      try { history.replaceState(null, "", stateToURL(getState())); } catch (e) { /* replaceState throttled */ }
    }, 150);
  }
  function flushURL() {
    if (urlTimer) { clearTimeout(urlTimer); urlTimer = null; }
    history.replaceState(null, "", stateToURL(getState()));
    return location.search;
  }

  function download(filename, blob) {
    const a = el("a", { href: URL.createObjectURL(blob), download: filename });
    document.body.append(a);
    a.click();
    setTimeout(() => { URL.revokeObjectURL(a.href); a.remove(); }, 1000);
  }

  // ------------------------------------------------------------------------
  // views: tabs in two panes
  // ------------------------------------------------------------------------
  const viewNodes = {};
  const viewData = {};   // plot view -> {header: [...], rows: [[...]]} for CSV and checks
  const TITLES = { lobe3d: "3D lobe", polar: "polar", theta_h: "θh", theta_d: "θd", theta_v: "θv", albedo: "albedo",
    sphere: "lit sphere", slice: "image slice", object: "lit object" };

  function setupViews() {
    for (const v of $$("#view-store .view")) {
      const name = v.dataset.view;
      viewNodes[name] = v;
      v.querySelector("canvas").dataset.view = name;
      const bar = el("div", { class: "export" });
      const png = el("button", { type: "button", class: "png", text: "PNG" });
      png.addEventListener("click", () => exportPNG(name));
      bar.append(png);
      if (!["sphere", "object"].includes(name)) {
        const csv = el("button", { type: "button", class: "csv", text: "CSV" });
        csv.addEventListener("click", () => exportCSV(name));
        bar.append(csv);
      }
      v.querySelector("h2").append(bar);
    }
    for (let i = 0; i < 2; i++) {
      const nav = $(`#pane-${i} .tabs`);
      for (const name of VIEWS) {
        const b = el("button", { type: "button", "data-view": name, text: TITLES[name] });
        b.addEventListener("click", () => { showView(name, i); changed(); });
        nav.append(b);
      }
    }
    showView(panes[0], 0);
    showView(panes[1], 1);
  }

  function showView(name, pane) {
    if (!VIEWS.includes(name)) throw new Error(`unknown view '${name}'; views: ${VIEWS.join(", ")}`);
    const other = 1 - pane;
    if (panes[other] === name) { // swap: a view lives in one pane at a time
      panes[other] = panes[pane];
    }
    panes[pane] = name;
    for (let i = 0; i < 2; i++) {
      const body = $(`#pane-${i} .pane-body`);
      const node = viewNodes[panes[i]];
      if (node.parentNode !== body) { body.textContent = ""; body.append(node); }
      for (const b of $$(`#pane-${i} .tabs button`)) b.classList.toggle("active", b.dataset.view === panes[i]);
    }
    for (const v of VIEWS) if (!panes.includes(v)) $("#view-store").append(viewNodes[v]);
  }

  function canvasOf(name) { return viewNodes[name].querySelector("canvas"); }

  function exportPNG(name) {
    drawView(name);
    canvasOf(name).toBlob((b) => download(`brdfkit-${name}.png`, b), "image/png");
  }
  // the slice's numbers: f_r on a 2° grid of (θh, θd) at the current φd, one row per grid point
  function sliceCSV() {
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
  function csvText(name) {
    drawView(name);
    if (name === "slice") viewData.sliceCSV = sliceCSV();
    const d = name === "slice" ? viewData.sliceCSV : viewData[name];
    if (!d) throw new Error(`view '${name}' has no numbers to export`);
    return [d.header.join(",")].concat(d.rows.map((r) => r.map((x) => (typeof x === "number" ? +x.toPrecision(8) : x)).join(","))).join("\n") + "\n";
  }
  function exportCSV(name) {
    try { download(`brdfkit-${name}.csv`, new Blob([csvText(name)], { type: "text/csv" })); } catch (e) { showError(e); }
  }

  // ------------------------------------------------------------------------
  // drawing helpers
  // ------------------------------------------------------------------------
  // the next frame draws every pane, or (drawOnly, a Set) only the views asked for
  let drawPending = false, drawOnly = null;
  function scheduleDraw(only) {
    if (!drawPending) drawOnly = only ? new Set([only]) : null;
    else if (drawOnly) { if (only) drawOnly.add(only); else drawOnly = null; }
    if (drawPending) return;
    drawPending = true;
    requestAnimationFrame(() => { const o = drawOnly; drawPending = false; drawOnly = null; draw(false, o); });
  }
  // a change of state; only: the one view it affects (the light of the lit sphere), else all
  function changed(only) { updateOutputs(); updateURL(); scheduleDraw(typeof only === "string" ? only : null); }
  const SPHERE_ONLY = new Set(["light-theta", "light-phi", "tangent"]);  // settings only the lit sphere reads

  function channelOf(f, k, ch) {
    const r = f[3 * k], g = f[3 * k + 1], b = f[3 * k + 2];
    if (ch === "r") return r;
    if (ch === "g") return g;
    if (ch === "b") return b;
    return 0.2126 * r + 0.7152 * g + 0.0722 * b;
  }
  // the curves of one BRDF for a plot: [{label, ys, dash}] per channel choice
  function channelCurves(panel, f, n, weight) {
    const ch = getSetting("channel");
    const chans = ch === "rgb" ? ["r", "g", "b"] : [ch];
    return chans.map((c, i) => ({
      panel, label: `${panel.model}${chans.length > 1 ? " " + c : ""}`, dash: [[], [6, 3], [2, 3]][i],
      ys: Array.from({ length: n }, (_, k) => channelOf(f, k, c) * (weight ? weight[k] : 1)),
    }));
  }
  function rgbColumns(panel) { return [`${panel.model}_r`, `${panel.model}_g`, `${panel.model}_b`]; }

  // copy the GL canvas's last image into a 2D canvas region
  function blit(ctx, w, h, dx, dy) { ctx.drawImage(glCanvas, 0, glCanvas.height - h, w, h, dx || 0, dy || 0, w, h); }
  function glSize(w, h) {
    if (glCanvas.width < w || glCanvas.height < h) {
      glCanvas.width = Math.max(glCanvas.width, w);
      glCanvas.height = Math.max(glCanvas.height, h);
    }
  }

  function plotFrame(ctx, W, H) {
    ctx.fillStyle = "#fff"; ctx.fillRect(0, 0, W, H);
    ctx.font = "13px system-ui, sans-serif";
  }
  function legend(ctx, curves, W) {
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
  function drawCartesian(canvas, xs, curves, xlabel, ylabel, opts) {
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

  const yLabel = () => (getSetting("ndotl") ? "f_r · cos θi" : "f_r [1/sr]");

  // directions in the plane of incidence: wi at (θi, φi), wo at signed angle a in the same plane
  function planeDirections(n) {
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

  // Rusinkiewicz (θh, θd, φd; φh = 0) -> (wi, wo), as the SLICE shader
  function fromHalfDiff(th, td, pd) {
    const h = [Math.sin(th), 0, Math.cos(th)];
    const bx = [Math.cos(th), 0, -Math.sin(th)];
    const d = [Math.sin(td) * Math.cos(pd), Math.sin(td) * Math.sin(pd), Math.cos(td)];
    const wi = [d[0] * bx[0] + d[2] * h[0], d[1], d[0] * bx[2] + d[2] * h[2]];
    const hw = h[0] * wi[0] + h[2] * wi[2];
    const wo = [2 * hw * h[0] - wi[0], -wi[1], 2 * hw * h[2] - wi[2]];
    return [wi, wo];
  }

  function nlWeights(wi, n) {
    if (!getSetting("ndotl")) return null;
    return Array.from({ length: n }, (_, k) => Math.max(0, wi[3 * k + 2]));
  }

  function evalPanels(wi, wo, n) {
    const out = [];
    for (const panel of visiblePanels()) {
      try { out.push({ panel, f: evaluateGPU(panel.model, panel.params(), wi, wo) }); } catch (e) { reportDrawError(e); }
    }
    return out;
  }
  let lastDrawError = null;
  function reportDrawError(e) {
    const m = String(e.message || e);
    if (m !== lastDrawError) { lastDrawError = m; showError("drawing failed: " + m); }
  }
  function csvFrom(header, xcols, evals, n) {
    const rows = [];
    for (let k = 0; k < n; k++) {
      const row = xcols.map((c) => c[k]);
      for (const e of evals) row.push(e.f[3 * k], e.f[3 * k + 1], e.f[3 * k + 2]);
      rows.push(row);
    }
    return { header: header.concat(...evals.map((e) => rgbColumns(e.panel))), rows };
  }

  // ------------------------------------------------------------------------
  // the views
  // ------------------------------------------------------------------------
  function drawPolar() {
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
    viewData.polar = Object.assign(csvFrom(["theta_o_deg"], [d.deg], evals, N), { peaks_deg: peaks, mirror_deg: num("theta-i") });
  }

  function drawThetaV() {
    const N = 361;
    const d = planeDirections(N);
    const evals = evalPanels(d.wi, d.wo, N);
    const wts = nlWeights(d.wi, N);
    const curves = [].concat(...evals.map((e) => channelCurves(e.panel, e.f, N, wts)));
    drawCartesian(canvasOf("theta_v"), d.deg, curves, "θv (signed, + on the mirror side)", yLabel(), { xticks: 30 });
    const peaks = curves.map((c) => d.deg[c.ys.indexOf(Math.max(...c.ys))]);
    viewData.theta_v = Object.assign(csvFrom(["theta_v_deg"], [d.deg], evals, N), { peaks_deg: peaks });
  }

  function drawHalfDiffPlot(view) {
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
    viewData[view] = csvFrom([view === "theta_h" ? "theta_h_deg" : "theta_d_deg"], [xs], evals, N);
  }

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
        scheduleDraw();
      }).catch((e) => { albedoCache[key] = { data: null, error: e.message }; showError(`albedo of ${panel.model}: ${e.message}`); });
    }
    return null;
  }
  function drawAlbedo() {
    const method = getSetting("albedo-method");
    const curves = [], evals = [];
    let xs = null, waiting = 0;
    for (const panel of visiblePanels()) {
      let d = null;
      try { d = method === "gpu" ? albedoGPU(panel) : albedoEngine(panel); } catch (e) { reportDrawError(e); }
      if (!d) { waiting++; continue; }
      if (kindOf(panel.model) === "merl" && method !== "gpu") continue;
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
    viewData.albedo = csvFrom(["theta_i_deg"], [xs], evals, xs.length);
  }

  function drawLobe3D() {
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
    const o = orbit.lobe3d;
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
    viewData.lobe3d = csvFrom(["theta_o_deg", "phi_o_deg"], [th, ph], evals, n);
  }

  // a row of square tiles, one per visible BRDF, each with a label line under it (LABEL_H),
  // in a canvas of the view's width; the canvas's height follows the row (at most its height
  // in index.html), so that no empty band is left below the tiles
  const LABEL_H = 18;
  function fitTiles(canvas, count) {
    if (!canvas.dataset.maxHeight) canvas.dataset.maxHeight = String(canvas.height);
    const W = canvas.width, H = +canvas.dataset.maxHeight;
    const n = Math.max(1, count);
    const w = Math.max(1, Math.min(Math.floor(W / n), H - LABEL_H));
    if (canvas.height !== w + LABEL_H) canvas.height = w + LABEL_H;
    const x0 = Math.floor((W - n * w) / 2);
    return Array.from({ length: n }, (_, i) => ({ x: x0 + i * w, y: 0, w, h: w }));
  }

  function lightDir() {
    const th = num("light-theta") * DEG, ph = num("light-phi") * DEG;
    return [Math.sin(th) * Math.cos(ph), Math.sin(th) * Math.sin(ph), Math.cos(th)];
  }

  function drawSphere(canvasArg) {
    const canvas = canvasArg || canvasOf("sphere");
    const ctx = canvas.getContext("2d");
    const list = visiblePanels();
    const T = fitTiles(canvas, list.length);
    const bgByte = Math.round(255 * srgbEncode(BACKGROUND));  // the spheres' own background, no band around them
    ctx.fillStyle = `rgb(${bgByte}, ${bgByte}, ${bgByte})`; ctx.fillRect(0, 0, canvas.width, canvas.height);
    const size = T[0].w;
    glSize(size * list.length, size);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.disable(gl.DEPTH_TEST);
    const L = lightDir();
    const scale = Math.PI * Math.pow(2, num("exposure"));
    list.forEach((panel, i) => {
      try {
        const prog = getProgram(sourceKey(panel.model), "sphere", intConstants(panel.model, panel.params()));
        gl.useProgram(prog);
        gl.viewport(i * size, 0, size, size);
        gl.uniform4f(U(prog, "bkw_viewport"), i * size, 0, size, size);
        gl.uniform3f(U(prog, "bkw_light"), L[0], L[1], L[2]);
        gl.uniform1f(U(prog, "bkw_scale"), scale);
        gl.uniform1i(U(prog, "bkw_tangent"), parseInt(getSetting("tangent"), 10));
        const bg = srgbEncode(BACKGROUND);
        gl.uniform3f(U(prog, "bkw_background"), bg, bg, bg);
        bindMaterial(prog, panel.model, panel.params());
        gl.drawArrays(gl.TRIANGLES, 0, 3);
      } catch (e) { reportDrawError(e); }
    });
    list.forEach((panel, i) => {
      ctx.drawImage(glCanvas, i * size, glCanvas.height - size, size, size, T[i].x, 0, size, size);
      ctx.fillStyle = panel.color; ctx.font = "13px system-ui, sans-serif";
      ctx.fillText(panel.model, T[i].x + 3, size + 14, size - 6);
    });
    viewData.sphere = { tiles: T.slice(0, list.length), models: list.map((p) => p.model) };
  }

  function drawSlice() {
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
    list.forEach((panel, i) => {
      ctx.drawImage(glCanvas, i * size, glCanvas.height - size, size, size, T[i].x, 0, size, size);
      ctx.fillStyle = panel.color; ctx.font = "13px system-ui, sans-serif";
      ctx.fillText(`${panel.model}  (φd = ${fmt(num("phi-d"))}°)`, T[i].x + 3, size + 14, size - 6);
    });
    viewData.slice = { tiles: T.slice(0, list.length), models: list.map((p) => p.model) };
  }

  // ---- the lit object: the renderer's pipeline ----
  const meshCache = {};
  let uploadedMesh = null;
  let meshPending = null;
  function meshBuffers(m) {
    const mk = (data, target) => { const b = gl.createBuffer(); gl.bindBuffer(target, b); gl.bufferData(target, data, gl.STATIC_DRAW); return b; };
    return {
      name: m.name, n: m.faces.length, triangles: m.faces.length / 3, vertices: m.positions.length / 3,
      pos: mk(Float32Array.from(m.positions), gl.ARRAY_BUFFER), nor: mk(Float32Array.from(m.normals), gl.ARRAY_BUFFER),
      tan: mk(Float32Array.from(m.tangents), gl.ARRAY_BUFFER), idx: mk(Uint32Array.from(m.faces), gl.ELEMENT_ARRAY_BUFFER),
    };
  }
  function currentMesh() {
    const name = getSetting("obj-mesh");
    if (name === "uploaded") return uploadedMesh;
    const key = name + ":" + getSetting("obj-tess");
    if (meshCache[key]) return meshCache[key];
    if (meshPending !== key) {
      meshPending = key;
      fetchJSON(`/api/mesh?name=${name}&tessellation=${getSetting("obj-tess")}`).then((m) => {
        meshCache[key] = meshBuffers(m); meshPending = null; scheduleDraw();
      }).catch((e) => { meshPending = null; showError(`mesh: ${e.message}`); });
    }
    return null;
  }
  const meshReady = () => currentMesh() !== null;

  function refreshObjectMaterials() {
    const s = $("#obj-material");
    if (!s) return;
    const cur = s.value;
    s.textContent = "";
    s.append(el("option", { value: "brdf:0", text: "BRDF: the first visible one" }));
    for (let i = 1; i < 8; i++) s.append(el("option", { value: `brdf:${i}`, text: `BRDF: visible number ${i + 1}` }));
    const g = el("optgroup", { label: "OpenGL fixed function (the lecture's table)" });
    for (const m of Object.keys(openglTable ? openglTable.materials : {})) g.append(el("option", { value: "gl:" + m, text: "OpenGL: " + m }));
    s.append(g);
    s.value = cur || "brdf:0";
    if (!s.value) s.value = "brdf:0";
  }

  function mat4Mul(a, b) { // column-major 4x4
    const o = new Float32Array(16);
    for (let c = 0; c < 4; c++) for (let r = 0; r < 4; r++) {
      let s = 0; for (let k = 0; k < 4; k++) s += a[k * 4 + r] * b[c * 4 + k]; o[c * 4 + r] = s;
    }
    return o;
  }
  function objectMatrices(w, h) {
    const o = orbit.object;
    const cy = Math.cos(o.yaw * DEG), sy = Math.sin(o.yaw * DEG), cp = Math.cos(o.pitch * DEG), sp = Math.sin(o.pitch * DEG);
    const ry = new Float32Array([cy, 0, -sy, 0, 0, 1, 0, 0, sy, 0, cy, 0, 0, 0, 0, 1]);
    const rx = new Float32Array([1, 0, 0, 0, 0, cp, sp, 0, 0, -sp, cp, 0, 0, 0, 0, 1]);
    const dist = 3.4 / o.zoom;
    const tr = new Float32Array([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, -dist, 1]);
    const mv = mat4Mul(tr, mat4Mul(rx, ry));
    const f = 1 / Math.tan(17.5 * DEG), near = 0.1, far = 50, asp = w / h;
    const proj = new Float32Array([f / asp, 0, 0, 0, 0, f, 0, 0, 0, 0, (far + near) / (near - far), -1, 0, 0, 2 * far * near / (near - far), 0]);
    const nm = new Float32Array([mv[0], mv[1], mv[2], mv[4], mv[5], mv[6], mv[8], mv[9], mv[10]]); // a rotation: its own inverse transpose
    return { mv, proj, nm };
  }

  function renderObject(w, h) {
    const mesh = currentMesh();
    glSize(w, h);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.viewport(0, glCanvas.height - h, w, h);
    gl.enable(gl.SCISSOR_TEST); gl.scissor(0, glCanvas.height - h, w, h);
    gl.clearColor(0.09, 0.09, 0.1, 1); gl.clearDepth(1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.disable(gl.SCISSOR_TEST);
    if (!mesh) return "loading the mesh…";
    const matSel = getSetting("obj-material");
    const shading = getSetting("obj-shading");
    const lighting = getSetting("obj-lighting");
    if (lighting.startsWith("env:")) return renderObjectIBL(mesh, w, h, lighting.slice(4), matSel);
    let prog, label, panel = null;
    if (matSel.startsWith("gl:")) {
      prog = getProgram("__opengl", "gl-" + shading);
      label = "OpenGL fixed function: " + matSel.slice(3);
    } else {
      const i = parseInt(matSel.slice(5), 10);
      panel = visiblePanels()[i];
      if (!panel) return `no visible BRDF number ${i + 1}`;
      prog = getProgram(sourceKey(panel.model), "obj-" + shading, intConstants(panel.model, panel.params()));
      label = panel.model;
    }
    const ambientAlbedo = panel ? normalAlbedo(panel) : null; // (runs the eval program: before useProgram)
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.viewport(0, glCanvas.height - h, w, h);
    gl.useProgram(prog);
    const M = objectMatrices(w, h);
    gl.uniformMatrix4fv(U(prog, "bkr_modelview"), false, M.mv);
    gl.uniformMatrix4fv(U(prog, "bkr_projection"), false, M.proj);
    gl.uniformMatrix3fv(U(prog, "bkr_normal_matrix"), false, M.nm);
    // one light, eye space (OpenGL's Light fields)
    const th = num("obj-light-theta") * DEG, ph = num("obj-light-phi") * DEG;
    const Ld = [Math.sin(th) * Math.cos(ph), Math.sin(th) * Math.sin(ph), Math.cos(th)]; // θ from the view axis
    const point = getSetting("obj-light-type") === "point";
    const dist = num("obj-light-dist"), camDist = 3.4 / orbit.object.zoom;
    const pos = point ? [Ld[0] * dist, Ld[1] * dist, Ld[2] * dist - camDist, 1] : [Ld[0], Ld[1], Ld[2], 0];
    const v3 = (x) => [x, x, x];
    gl.uniform1i(U(prog, "bkr_num_lights"), 1);
    gl.uniform4fv(U(prog, "bkr_light_position[0]"), pos);
    gl.uniform3fv(U(prog, "bkr_light_ambient[0]"), v3(num("obj-light-ambient")));
    gl.uniform3fv(U(prog, "bkr_light_diffuse[0]"), v3(num("obj-light-diffuse")));
    gl.uniform3fv(U(prog, "bkr_light_specular[0]"), v3(num("obj-light-specular")));
    gl.uniform3fv(U(prog, "bkr_light_attenuation[0]"), [num("obj-att-c"), num("obj-att-l"), num("obj-att-q")]);
    gl.uniform3fv(U(prog, "bkr_light_spot_direction[0]"), [0, 0, -1]);
    gl.uniform1fv(U(prog, "bkr_light_spot_exponent[0]"), [0]);
    gl.uniform1fv(U(prog, "bkr_light_spot_cos_cutoff[0]"), [-2]);
    gl.uniform3fv(U(prog, "bkr_scene_ambient"), v3(num("obj-scene-ambient")));
    gl.uniform1i(U(prog, "bkr_local_viewer"), getSetting("obj-local-viewer") ? 1 : 0);
    if (panel) {
      bindMaterial(prog, panel.model, panel.params());
      gl.uniform3fv(U(prog, "bkr_ambient_albedo"), ambientAlbedo);
    } else {
      const m = openglTable.materials[matSel.slice(3)];
      for (const f of ["ambient", "diffuse", "specular", "emission"]) gl.uniform4fv(U(prog, "bkr_mat_" + f), m[f]);
      gl.uniform1f(U(prog, "bkr_mat_shininess"), m.shininess);
    }
    const A = prog._attr;
    for (const [loc, buf] of [[A.position, mesh.pos], [A.normal, mesh.nor], [A.tangent, mesh.tan]]) {
      if (loc < 0) continue;
      gl.bindBuffer(gl.ARRAY_BUFFER, buf);
      gl.enableVertexAttribArray(loc);
      gl.vertexAttribPointer(loc, 3, gl.FLOAT, false, 0, 0);
    }
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, mesh.idx);
    gl.enable(gl.DEPTH_TEST);
    gl.depthFunc(gl.LESS);
    gl.drawElements(gl.TRIANGLES, mesh.n, gl.UNSIGNED_INT, 0);
    gl.disable(gl.DEPTH_TEST);
    for (const loc of [A.position, A.normal, A.tangent]) if (loc >= 0) gl.disableVertexAttribArray(loc);
    return `${label} · ${mesh.name}: ${mesh.triangles} triangles, ${mesh.vertices} vertices · ${shading} shading · ${point ? "point" : "directional"} light`;
  }
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
        scheduleDraw();
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
      fetchJSON("/api/ibl/sampler?" + q.toString()).then((u) => { samplerCache[key] = { u }; scheduleDraw(); })
        .catch(() => { samplerCache[key] = { u: { bki_lobe: 0, bki_lobe_params: [0, 0], bki_diffuse_prob: 1 } }; scheduleDraw(); });
    }
    return null;
  }
  function renderObjectIBL(mesh, w, h, envName, matSel) {
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
      const M = objectMatrices(w, h);
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
      const e2m = new Float32Array(9);  // column-major: e2m[c*3+r] = Σ_k W2M[r][k] · (R^T)[k][c]
      for (let r = 0; r < 3; r++) for (let c = 0; c < 3; c++) {
        let sum = 0;
        for (let k = 0; k < 3; k++) sum += W2M[r * 3 + k] * R[k * 3 + c];  // (R^T)[k][c] = R[c][k] = R_colmajor[k*3 + c]
        e2m[c * 3 + r] = sum;
      }
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
        out.data[d + c] = cov ? Math.round(255 * linearToSrgb(Math.min(1, Math.max(0, isFinite(v) ? v : 0)))) : bg[c];
      }
      out.data[d + 3] = 255;
    }
    ibl.image = out;
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    if (ibl.spp < iblMax()) ibl.pending = true;
    return `${panel.model} · ${mesh.name} · environment ${envName} (no shadows; the map is not drawn behind) · `
      + `${ibl.spp} of ${iblMax()} samples per pixel (MIS of the BRDF's sampler and the map's luminance), sRGB`;
  }
  const iblDone = () => ibl.spp >= iblMax();

  // ρ at normal incidence for the ambient term (pipeline_brdf.glsl's bkr_ambient_albedo), GPU quadrature
  const normalAlbedoCache = {};
  function normalAlbedo(panel) {
    const key = panel.model + JSON.stringify(panel.params());
    if (normalAlbedoCache[key]) return normalAlbedoCache[key];
    const S = 32, n = S * S, wi = new Float32Array(3 * n), wo = new Float32Array(3 * n);
    for (let k = 0; k < n; k++) {
      const u = (Math.floor(k / S) + 0.5) / S, v = (k % S + 0.5) / S, r = Math.sqrt(u), p = 2 * Math.PI * v;
      wi.set([0, 0, 1], 3 * k); wo.set([r * Math.cos(p), r * Math.sin(p), Math.sqrt(1 - u)], 3 * k);
    }
    const f = evaluateGPU(panel.model, panel.params(), wi, wo);
    const s = [0, 0, 0];
    for (let k = 0; k < n; k++) for (let c = 0; c < 3; c++) s[c] += f[3 * k + c] * Math.PI / n;
    normalAlbedoCache[key] = s;
    return s;
  }

  function drawObject(canvasArg) {
    const canvas = canvasArg || canvasOf("object");
    const ctx = canvas.getContext("2d");
    let note = "";
    ibl.image = null;
    try { note = renderObject(canvas.width, canvas.height); } catch (e) { reportDrawError(e); note = "failed: " + e.message; }
    if (ibl.image) ctx.putImageData(ibl.image, 0, 0);
    else blit(ctx, canvas.width, canvas.height);
    $("#object-note").textContent = note;
  }

  const DRAW = {
    lobe3d: drawLobe3D, polar: drawPolar, theta_h: () => drawHalfDiffPlot("theta_h"), theta_d: () => drawHalfDiffPlot("theta_d"),
    theta_v: drawThetaV, albedo: drawAlbedo, sphere: () => drawSphere(), slice: drawSlice, object: () => drawObject(),
  };
  function drawView(name) {
    if (!gl) return;
    DRAW[name]();
    status.drawn[name] = (status.drawn[name] || 0) + 1;
  }

  // onlyObject: the progressive environment-lit object's next pass; views: a Set, or null for all
  function draw(onlyObject, views) {
    if (!gl) return;
    updateOutputs();
    const list = panes.filter((v) => (views ? views.has(v) : (!onlyObject || v === "object")));
    if (list.includes("object")) ibl.pending = false;  // (else a progressive object keeps its next pass)
    for (const v of list) drawView(v);
    status.frames += 1;
    if (ibl.pending && panes.includes("object")) {  // progressive: another pass of the lit object next frame
      requestAnimationFrame(() => { if (!drawPending) draw(true); });
    }
  }

  // ------------------------------------------------------------------------
  // mouse: drag the light on the sphere, orbit/zoom the lobe and the object
  // ------------------------------------------------------------------------
  function setupMouse() {
    const sphere = canvasOf("sphere");
    const moveLight = (ev) => {
      const r = sphere.getBoundingClientRect();
      const x = (ev.clientX - r.left) * sphere.width / r.width, y = (ev.clientY - r.top) * sphere.height / r.height;
      const T = (viewData.sphere && viewData.sphere.tiles) || [];
      for (const t of T) {
        if (x < t.x || x >= t.x + t.w || y >= t.h) continue;
        const px = ((x - t.x) / t.w * 2 - 1) * 1.06, py = -(y / t.h * 2 - 1) * 1.06;
        const r2 = px * px + py * py;
        if (r2 >= 1) return;
        // the light along the normal under the cursor: that point is lit head-on
        const nz = Math.sqrt(1 - r2);
        setSetting("light-theta", Math.round(Math.acos(nz) / DEG * 2) / 2);
        setSetting("light-phi", Math.round(((Math.atan2(py, px) / DEG + 360) % 360) * 2) / 2);
        changed("sphere");
        return;
      }
    };
    let dragging = false;
    sphere.addEventListener("pointerdown", (e) => { dragging = true; sphere.setPointerCapture(e.pointerId); moveLight(e); });
    sphere.addEventListener("pointermove", (e) => { if (dragging) moveLight(e); });
    sphere.addEventListener("pointerup", () => { dragging = false; });
    for (const name of ["lobe3d", "object"]) {
      const c = canvasOf(name);
      let last = null;
      c.addEventListener("pointerdown", (e) => { last = [e.clientX, e.clientY]; c.setPointerCapture(e.pointerId); });
      c.addEventListener("pointermove", (e) => {
        if (!last) return;
        const o = orbit[name];
        o.yaw += (e.clientX - last[0]) * 0.5;
        o.pitch = Math.max(-89, Math.min(89, o.pitch + (e.clientY - last[1]) * 0.5));
        last = [e.clientX, e.clientY];
        changed();
      });
      c.addEventListener("pointerup", () => { last = null; });
      c.addEventListener("wheel", (e) => {
        e.preventDefault();
        orbit[name].zoom = Math.max(0.2, Math.min(8, orbit[name].zoom * Math.exp(-e.deltaY * 0.001)));
        changed();
      }, { passive: false });
    }
  }

  // ------------------------------------------------------------------------
  // files: drop or open
  // ------------------------------------------------------------------------
  async function openFile(file) {
    const name = file.name.toLowerCase();
    try {
      if (name.endsWith(".json")) {
        let st;
        try { st = JSON.parse(await file.text()); } catch (e) { throw new Error(`${file.name}: not valid JSON (${e.message})`); }
        await applyState(st, file.name);
      } else if (fileLoader(name)) {
        const label = await loadAndKeep(file.name, await file.arrayBuffer());
        if (label === "obj") {
          setSetting("obj-mesh", "uploaded");
          if (!panes.includes("object")) showView("object", 1);
        } else addPanel(label, {});
        changed();
      } else {
        throw new Error(`${file.name}: unknown file type; drop a .json view, a MERL .binary, a .brdf or an .obj`);
      }
    } catch (e) { showError(e); }
  }

  function setupFiles() {
    $("#file-input").addEventListener("change", async (e) => {
      for (const f of Array.from(e.target.files)) await openFile(f);
      e.target.value = "";
    });
    document.addEventListener("dragover", (e) => { e.preventDefault(); document.body.classList.add("dropping"); });
    document.addEventListener("dragleave", () => document.body.classList.remove("dropping"));
    document.addEventListener("drop", async (e) => {
      e.preventDefault();
      document.body.classList.remove("dropping");
      for (const f of Array.from(e.dataTransfer.files)) await openFile(f);
    });
    $("#save-state").addEventListener("click", () => {
      download("brdfkit-view.json", new Blob([JSON.stringify(getState(), null, 2) + "\n"], { type: "application/json" }));
    });
  }

  // ------------------------------------------------------------------------
  // start-up
  // ------------------------------------------------------------------------
  async function start() {
    glCanvas = document.createElement("canvas");
    glCanvas.width = 560; glCanvas.height = 420;
    gl = glCanvas.getContext("webgl2", { antialias: false, preserveDrawingBuffer: true, depth: true });
    if (!gl) {
      status.error = "WebGL 2 is not available in this browser";
      setStatus(status.error, true);
      status.ready = true;
      return;
    }
    status.webgl2 = true;
    status.floatTargets = !!gl.getExtension("EXT_color_buffer_float");
    status.renderer = gl.getParameter(gl.RENDERER);
    const [list, measured, gltab] = await Promise.all([
      fetchJSON("/api/models").then((b) => b.models), fetchJSON("/api/measured").then((b) => b.materials), fetchJSON("/api/opengl")]);
    measuredNames = measured;
    openglTable = gltab;
    const files = ["pipeline_lights.glsl", "pipeline_vertex.glsl", "pipeline_fragment.glsl", "pipeline_brdf.glsl", "opengl_fixed.glsl"];
    const texts = await Promise.all(files.map((f) => fetchText("/api/glsl?file=" + f)));
    files.forEach((f, i) => { shaderFiles[f] = texts[i]; });
    try {  // image-based lighting: the renderer's ibl*.glsl and the built-in maps
      const [a, b, envs] = await Promise.all([fetchText("/api/glsl?file=ibl_sampling.glsl"), fetchText("/api/glsl?file=ibl.glsl"),
        fetchJSON("/api/envs")]);
      shaderFiles["ibl_sampling.glsl"] = a; shaderFiles["ibl.glsl"] = b;
      for (const [name, doc] of Object.entries(envs.environments)) $("#obj-lighting").append(el("option", { value: "env:" + name, text: "environment: " + name, title: doc }));
    } catch (e) { /* a server without image-based lighting: point lights only */ }
    const srcs = await Promise.all(list.map((m) => (m.glsl ? fetchText("/api/shader/" + encodeURIComponent(m.name)).catch(() => null) : null)));
    list.forEach((m, i) => {
      modelInfo[m.name] = m;
      const st = { ok: false, error: null, sphere: false, eval: false };
      status.models[m.name] = st;
      if (srcs[i] === null) { st.error = "no GLSL source"; return; }
      sources[m.name] = srcs[i];
      try {
        getProgram(m.name, "sphere"); st.sphere = true;
        getProgram(m.name, "eval"); st.eval = true;
        st.ok = true;
      } catch (e) {
        st.error = e.message.split("\n")[0];
        console.error(`brdfkit: model ${m.name}: ${e.message}`);
      }
    });
    setupViews();
    setupMouse();
    setupFiles();
    refreshObjectMaterials();
    for (const id of Object.keys(SETTINGS)) {
      DEFAULTS[id] = getSetting(id);
      const only = SPHERE_ONLY.has(id) ? "sphere" : null;
      $("#" + id).addEventListener("input", () => changed(only));
      $("#" + id).addEventListener("change", () => changed(only));
    }
    $("#add-brdf").addEventListener("click", () => {
      const taken = new Set(panels.map((p) => p.model));
      const next = Object.keys(modelInfo).find((n) => !taken.has(n)) || Object.keys(modelInfo)[0];
      addPanel(next, {});
      changed();
    });
    $("#reset-all").addEventListener("click", () => resetAll());
    const defaultModel = modelInfo.microfacet ? "microfacet" : list[0].name;
    if (location.search) await loadURL(location.search);
    if (!panels.length) addPanel(defaultModel, {});
    const bad = Object.entries(status.models).filter(([, s]) => !s.ok).map(([n]) => n);
    setStatus(`${list.length} models + ${measuredNames.length} measured, ${bad.length ? "shader errors: " + bad.join(", ") : "all shaders compiled"} · ${status.renderer}`
      + (status.floatTargets ? "" : " · no float render targets"), bad.length > 0);
    updateOutputs();
    draw();
    flushURL();
    status.ready = true;
  }

  // a URL query (the page's own, or one given by a script) -> the state, errors shown on the page
  async function loadURL(search) {
    let st = null;
    try { st = urlToState(search); } catch (e) { showError(e); }
    if (st && !st.model) { showError("URL: missing 'model' (the first BRDF's name)"); st.model = undefined; }
    if (st) await applyState(st, "URL");
  }

  function resetAll() {
    for (const p of panels.slice()) p.root.remove();
    panels.length = 0;
    addPanel(modelInfo.microfacet ? "microfacet" : Object.keys(modelInfo)[0], {});
    for (const [k, v] of Object.entries(DEFAULTS)) setSetting(k, v);
    Object.assign(orbit.lobe3d, ORBIT_DEFAULTS.lobe3d);
    Object.assign(orbit.object, ORBIT_DEFAULTS.object);
    clearErrors();
    changed();
  }

  // ------------------------------------------------------------------------
  // the page's API for scripts and tests (SPEC.md: eval, views, state)
  // ------------------------------------------------------------------------
  window.brdfkit = {
    // Promise of [r, g, b] for one (wi, wo), or a list of them for lists of directions
    eval: async (name, params, wi, wo) => {
      await ensureLoaded(name);
      const many = Array.isArray(wi[0]);
      const a = many ? flat3(wi) : Float32Array.from(wi), b = many ? flat3(wo) : Float32Array.from(wo);
      const norm = (v) => { for (let k = 0; k < v.length; k += 3) { const l = Math.hypot(v[k], v[k + 1], v[k + 2]); if (!(l > 0)) throw new Error("the zero vector is not a direction"); v[k] /= l; v[k + 1] /= l; v[k + 2] /= l; } return v; };
      if (kindOf(name) === "analytic") {
        const q = JSON.stringify(params || {});
        if (!validatedCache.has(name + q)) { await validated(name, params || {}); validatedCache.add(name + q); }
      }
      const f = evaluateGPU(name, params || {}, norm(a), norm(b));
      const out = [];
      for (let k = 0; k < f.length; k += 3) out.push([f[k], f[k + 1], f[k + 2]]);
      return many ? out : out[0];
    },
    views: () => VIEWS.slice(),
    state: () => getState(),
    setState: (st) => applyState(st, "setState"),
    url: () => flushURL(),
    loadURL: (search) => loadURL(search),
    show: (view, pane) => { showView(view, pane === undefined ? 0 : pane); draw(); },
    render: (view) => { drawView(view); return canvasOf(view).toDataURL("image/png"); },
    data: (view) => { drawView(view); return viewData[view] || null; },
    csv: (view) => csvText(view),
    canvas: (view) => canvasOf(view),
    panels,
    addBRDF: async (name, params) => { await ensureLoaded(name); const p = addPanel(name, params || {}); changed(); return p.id; },
    errors: () => errorList.slice(),
    redraw: () => draw(),
    openFile: (file) => openFile(file),
    meshReady: () => meshReady(),
    iblDone: () => iblDone(),
    // the older synchronous form: a flat [r, g, b, r, g, b, ...] for lists of directions (analytic models)
    evaluate: (name, params, wi, wo) => Array.from(evaluateGPU(name, params, flat3(wi), flat3(wo))),
    evaluateNumpy: async (name, params, wi, wo) => Array.from(await evaluateNumpy(name, params, wi, wo)),
    // frames per second of one view drawn into a w x h canvas (gl.finish each frame):
    // `frames` frames, or fewer (at least 3) once `budgetS` seconds have passed
    bench: (view, w, h, frames, budgetS) => {
      const c = document.createElement("canvas");
      c.width = w; c.height = h;
      const fn = view === "sphere" ? () => drawSphere(c) : () => drawObject(c);
      fn(); gl.finish();
      const t0 = performance.now();
      let n = 0;
      while (n < frames && (n < 3 || !budgetS || performance.now() - t0 < 1000 * budgetS)) { fn(); gl.finish(); n++; }
      const dt = (performance.now() - t0) / 1000;
      return { fps: n / dt, seconds: dt, frames: n, width: w, height: h };
    },
  };
  const validatedCache = new Set();

  start().catch((e) => {
    status.error = String(e && e.message || e);
    setStatus("start-up failed: " + status.error, true);
    status.ready = true;
  });
})();
