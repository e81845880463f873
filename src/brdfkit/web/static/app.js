// brdfkit explorer: plain JavaScript + WebGL 2, no build step, nothing fetched from outside.
//
// The page asks the server for the models' parameter specs (/api/models) and their
// GLSL ES sources (/api/shader/<model>, defining vec3 brdf(vec3 wi, vec3 wo) in the
// local frame n = +z, t = +x), compiles every model twice in one WebGL 2 context:
//   * a sphere program: ray-sphere in screen space, local frame from the normal and a
//     tangent, one directional light, exposure, sRGB;
//   * an evaluation program: brdf() for direction pairs read from float textures,
//     written to an RGBA32F render target and read back (the polar plot and
//     window.brdfkit.evaluate, which the tests compare with numpy).
// window.brdfkitStatus reports readiness and per-model compile errors.
"use strict";

(function () {
  const status = {
    ready: false, webgl2: false, floatTargets: false, renderer: null,
    models: {}, error: null, frames: 0,
  };
  window.brdfkitStatus = status;

  const $ = (sel, root) => (root || document).querySelector(sel);
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

  function setStatus(text, isError) {
    const s = $("#status");
    s.textContent = text;
    s.classList.toggle("error", !!isError);
  }

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
  const linearToSrgb = (c) => (c <= 0.0031308 ? 12.92 * c : 1.055 * Math.pow(c, 1 / 2.4) - 0.055);

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
      // log sliders span at most 5 decades below the top (0 is reached at t = 0)
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
  const BACKGROUND = 0.06; // linear grey behind the spheres (the unlit side stays black)

  // ------------------------------------------------------------------------
  // GL
  // ------------------------------------------------------------------------
  const VERT = `#version 300 es
void main() {
    vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
`;
  const SPHERE_MAIN = `
uniform vec4 bkw_viewport;     // x, y, w, h in pixels
uniform vec3 bkw_light;        // unit, view space (viewer along +z)
uniform float bkw_scale;       // light irradiance x 2^exposure
uniform int bkw_tangent;       // 0: tangents along latitudes, 1: along longitudes
uniform vec3 bkw_background;
out vec4 bkw_color;
// IEC 61966-2-1 sRGB encoding, as linearToSrgb above
float bkw_srgb1(float c) { return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055; }
vec3 bkw_srgb(vec3 c) { c = clamp(c, 0.0, 1.0); return vec3(bkw_srgb1(c.r), bkw_srgb1(c.g), bkw_srgb1(c.b)); }
void main() {
    vec2 p = ((gl_FragCoord.xy - bkw_viewport.xy) / bkw_viewport.zw * 2.0 - 1.0) * 1.06;
    float r2 = dot(p, p);
    if (r2 >= 1.0) { bkw_color = vec4(bkw_srgb(bkw_background), 1.0); return; }
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
    // antialiased silhouette
    float r = sqrt(r2);
    float a = clamp((1.0 - r) / max(fwidth(r), 1e-6), 0.0, 1.0);
    bkw_color = vec4(mix(bkw_srgb(bkw_background), bkw_srgb(c), a), 1.0);
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
  const programs = {}; // name -> {sphere, eval, uniforms: {sphere: {}, eval: {}}}

  function compileProgram(fragSource) {
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
    const vs = mk(gl.VERTEX_SHADER, VERT);
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
    return prog;
  }

  function uniformLocations(prog, info) {
    const out = {};
    for (const p of info.params) out[p.name] = gl.getUniformLocation(prog, p.uniform.name);
    return out;
  }

  // the uniform values of a parameter set (a plain object, as for /api/eval)
  function setModelUniforms(locs, info, values) {
    for (const p of info.params) {
      const loc = locs[p.name];
      let v = values[p.name];
      if (loc === null || v === null || v === undefined) continue; // unused, or undefined (alpha when anisotropic)
      if (p.kind === "scalar") gl.uniform1f(loc, +v);
      else if (p.kind === "rgb") {
        if (!Array.isArray(v)) v = [v, v, v];
        gl.uniform3f(loc, +v[0], +v[1], +v[2]);
      } else if (p.kind === "bool") gl.uniform1i(loc, v === true || v === 1 || v === "true" ? 1 : 0);
      else if (p.kind === "choice") gl.uniform1i(loc, Math.max(0, p.choices.indexOf(v)));
      else gl.uniform1i(loc, Math.round(+v));
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
  // evaluation on the GPU: brdf() for N direction pairs -> Float32Array(3N)
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
    const P = programs[name];
    if (!P || !P.eval) throw new Error(`model '${name}' is not compiled: ${status.models[name] && status.models[name].error}`);
    const info = modelInfo[name];
    const n = wi.length;
    if (wo.length !== n) throw new Error("wi and wo must have the same length");
    const w = Math.min(n, 1024), h = Math.max(1, Math.ceil(n / w));
    const a = new Float32Array(w * h * 4), b = new Float32Array(w * h * 4);
    for (let k = 0; k < n; k++) {
      a[4 * k] = wi[k][0]; a[4 * k + 1] = wi[k][1]; a[4 * k + 2] = wi[k][2];
      b[4 * k] = wo[k][0]; b[4 * k + 1] = wo[k][1]; b[4 * k + 2] = wo[k][2];
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
    gl.useProgram(P.eval);
    gl.activeTexture(gl.TEXTURE0); gl.bindTexture(gl.TEXTURE_2D, evalRes.wi);
    gl.activeTexture(gl.TEXTURE1); gl.bindTexture(gl.TEXTURE_2D, evalRes.wo);
    gl.uniform1i(P.evalSamplers.wi, 0);
    gl.uniform1i(P.evalSamplers.wo, 1);
    setModelUniforms(P.evalUniforms, info, effectiveParams(info, params));
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    const out = new Float32Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.FLOAT, out);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    const res = new Float32Array(3 * n);
    for (let k = 0; k < n; k++) {
      res[3 * k] = out[4 * k]; res[3 * k + 1] = out[4 * k + 1]; res[3 * k + 2] = out[4 * k + 2];
    }
    return res;
  }

  // the same through the server's numpy (/api/eval), a fallback and the cross-check
  async function evaluateNumpy(name, params, wi, wo) {
    const q = new URLSearchParams({ model: name, params: JSON.stringify(params || {}),
      wi: JSON.stringify(wi), wo: JSON.stringify(wo) });
    const r = await fetch("/api/eval?" + q.toString());
    const body = await r.json();
    if (!r.ok) throw new Error(body.error || r.statusText);
    return Float32Array.from(body.value.flat());
  }

  // ------------------------------------------------------------------------
  // the parameter panels
  // ------------------------------------------------------------------------
  let modelInfo = {};
  const panels = {};

  class Panel {
    constructor(id, optional) {
      this.root = $("#" + id);
      this.select = $(".model-select", this.root);
      this.paramsBox = $(".params", this.root);
      this.title = $(".model-title", this.root);
      this.optional = optional;
      this.model = null;
      this.values = {};
      this.controls = {};
      this.select.addEventListener("change", () => this.setModel(this.select.value));
      $(".reset", this.root).addEventListener("click", () => this.setModel(this.model));
    }

    setModel(name) {
      this.model = name || null;
      this.paramsBox.textContent = "";
      this.controls = {};
      this.values = {};
      $(".reset", this.root).style.display = name ? "" : "none";
      if (!name) { this.title.textContent = ""; scheduleDraw(); return; }
      this.select.value = name;
      const info = modelInfo[name];
      const st = status.models[name];
      this.title.textContent = info.title + (st && !st.ok ? "  [shader error: " + st.error + "]" : "");
      this.title.title = info.reference;
      this.values = effectiveParams(info, {});
      for (const p of info.params) this.paramsBox.append(this.makeControl(p));
      this.refreshAll();
      scheduleDraw();
    }

    makeControl(p) {
      const row = el("div", { class: "param", "data-param": p.name, title: `${p.doc} — allowed ${p.range}` });
      const label = el("span", { class: "name" }, p.name);
      if (p.unit) label.append(" ", el("small", { text: p.unit }));
      row.append(label);
      const c = { p, row };
      this.controls[p.name] = c;
      const changed = () => { this.onChange(p.name); scheduleDraw(); };
      if (p.kind === "choice") {
        const s = el("select", {});
        for (const ch of p.choices) s.append(el("option", { value: ch, text: ch }));
        s.addEventListener("change", () => { this.values[p.name] = s.value; changed(); });
        c.select = s; row.append(s);
      } else if (p.kind === "bool") {
        const cb = el("input", { type: "checkbox" });
        cb.addEventListener("change", () => { this.values[p.name] = cb.checked; changed(); });
        c.checkbox = cb; row.append(el("span", { class: "rgb" }, cb));
      } else if (p.kind === "scalar" || p.kind === "int") {
        const map = sliderMap(p);
        const slider = el("input", { type: "range", min: "0", max: String(STEPS), step: "1" });
        const num = el("input", { type: "number", step: "any" });
        slider.addEventListener("input", () => {
          let v = map.toValue(slider.value / STEPS);
          if (p.kind === "int") v = Math.round(v);
          this.values[p.name] = v; num.value = fmt(v); changed();
        });
        num.addEventListener("change", () => {
          let v = parseFloat(num.value);
          if (!isFinite(v)) v = this.values[p.name] === null ? p.default : this.values[p.name];
          v = map.clamp(v);
          if (p.kind === "int") v = Math.round(v);
          this.values[p.name] = v; this.refresh(p.name); changed();
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
        const box = el("span", { class: "rgb" });
        const fields = [0, 1, 2].map((i) => el("input", { type: "number", step: "any", title: "rgb"[i] }));
        let picker = null;
        if (map.lo >= 0 && map.hi <= 1) {
          picker = el("input", { type: "color", title: "pick a colour (sRGB, converted to linear)" });
          picker.addEventListener("input", () => {
            const hex = picker.value;
            const lin = [1, 3, 5].map((i) => srgbToLinear(parseInt(hex.slice(i, i + 2), 16) / 255));
            this.values[p.name] = lin.map((x) => map.clamp(x));
            this.refresh(p.name, "picker"); changed();
          });
          box.append(picker);
        }
        box.append(...fields);
        slider.addEventListener("input", () => {
          const target = map.toValue(slider.value / STEPS);
          this.values[p.name] = this.scaleTriple(p.name, target, map);
          this.refresh(p.name, "slider"); changed();
        });
        level.addEventListener("change", () => {
          const target = parseFloat(level.value);
          if (isFinite(target)) this.values[p.name] = this.scaleTriple(p.name, map.clamp(target), map);
          this.refresh(p.name); changed();
        });
        fields.forEach((f, i) => f.addEventListener("change", () => {
          const v = this.triple(p.name).slice();
          const x = parseFloat(f.value);
          if (isFinite(x)) v[i] = map.clamp(x);
          this.values[p.name] = v;
          this.refresh(p.name); changed();
        }));
        Object.assign(c, { map, slider, level, fields, picker });
        row.append(slider, level, el("span", {}), box);
      }
      return row;
    }

    triple(name) {
      const v = this.values[name];
      return Array.isArray(v) ? v.map(Number) : [+v, +v, +v];
    }

    // the triple scaled so that its largest channel is `target` (grey if it was black)
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
      // alpha (isotropic shorthand) <-> alpha_x, alpha_y
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

    // parameters as JSON for /api/eval and evaluate() (alpha left out when undefined)
    params() {
      const out = {};
      for (const [k, v] of Object.entries(this.values)) if (v !== null) out[k] = v;
      if ("alpha" in out && "alpha_x" in out) delete out.alpha;
      return out;
    }
  }

  // ------------------------------------------------------------------------
  // drawing
  // ------------------------------------------------------------------------
  const sceneInputs = ["light-theta", "light-phi", "exposure", "tangent", "theta-i", "plane-phi", "channel", "scale"];
  let drawPending = false;
  function scheduleDraw() {
    if (drawPending) return;
    drawPending = true;
    requestAnimationFrame(() => { drawPending = false; draw(); });
  }

  function num(id) { return parseFloat($("#" + id).value); }

  function activePanels() {
    return ["main", "compare"].map((k) => panels[k]).filter((p) => p.model && programs[p.model] && programs[p.model].sphere);
  }

  function drawSphere() {
    const canvas = $("#sphere");
    const list = activePanels();
    const size = 300;
    const want = Math.max(1, list.length) * size;
    if (canvas.width !== want) { canvas.width = want; canvas.style.width = want + "px"; }
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.viewport(0, 0, canvas.width, canvas.height);
    gl.clearColor(0, 0, 0, 1);
    gl.clear(gl.COLOR_BUFFER_BIT);
    const th = num("light-theta") * Math.PI / 180, ph = num("light-phi") * Math.PI / 180;
    const L = [Math.sin(th) * Math.cos(ph), Math.sin(th) * Math.sin(ph), Math.cos(th)];
    // a unit-radiance white light: E = π so that a white Lambertian surface facing it shows 1.0
    const scale = Math.PI * Math.pow(2, num("exposure"));
    list.forEach((panel, i) => {
      const P = programs[panel.model];
      gl.useProgram(P.sphere);
      gl.viewport(i * size, 0, size, size);
      const u = P.sphereScene;
      gl.uniform4f(u.viewport, i * size, 0, size, size);
      gl.uniform3f(u.light, L[0], L[1], L[2]);
      gl.uniform1f(u.scale, scale);
      gl.uniform1i(u.tangent, parseInt($("#tangent").value, 10));
      gl.uniform3f(u.background, BACKGROUND, BACKGROUND, BACKGROUND);
      setModelUniforms(P.sphereUniforms, modelInfo[panel.model], effectiveParams(modelInfo[panel.model], panel.params()));
      gl.drawArrays(gl.TRIANGLES, 0, 3);
    });
    $("#label-main").textContent = list[0] ? list[0].model : "";
    $("#label-compare").textContent = list[1] ? "compare: " + list[1].model : "";
    $("#label-compare").style.display = list[1] ? "" : "none";
  }

  // the in-plane directions of the lobe plot: wi at -θi, wo from -90° to +90°
  const NPOLAR = 361;

  function polarDirections() {
    const ti = num("theta-i") * Math.PI / 180, ph = num("plane-phi") * Math.PI / 180;
    const c = Math.cos(ph), s = Math.sin(ph);
    const wi = [], wo = [], angles = [];
    const wiv = [-Math.sin(ti) * c, -Math.sin(ti) * s, Math.cos(ti)];
    for (let k = 0; k < NPOLAR; k++) {
      // open ends: ±89.9° keeps wo above the horizon
      const a = (-89.9 + 179.8 * k / (NPOLAR - 1)) * Math.PI / 180;
      angles.push(a);
      wi.push(wiv);
      wo.push([Math.sin(a) * c, Math.sin(a) * s, Math.cos(a)]);
    }
    return { wi, wo, angles, ti };
  }

  function channelValue(f, k, ch) {
    const r = f[3 * k], g = f[3 * k + 1], b = f[3 * k + 2];
    if (ch === "r") return r;
    if (ch === "g") return g;
    if (ch === "b") return b;
    return 0.2126 * r + 0.7152 * g + 0.0722 * b;
  }

  function drawPolar() {
    const canvas = $("#polar");
    const ctx = canvas.getContext("2d");
    const W = canvas.width, H = canvas.height;
    ctx.clearRect(0, 0, W, H);
    const cx = W / 2, cy = H - 24, R = Math.min(W / 2 - 20, H - 44);
    const dirs = polarDirections();
    const ch = $("#channel").value, logScale = $("#scale").value === "log";
    const curves = [];
    for (const [key, panel] of [["main", panels.main], ["compare", panels.compare]]) {
      if (!panel.model || !programs[panel.model] || !programs[panel.model].eval) continue;
      try {
        const f = evaluateGPU(panel.model, panel.params(), dirs.wi, dirs.wo);
        const ys = dirs.angles.map((a, k) => Math.max(0, channelValue(f, k, ch) * Math.cos(a)));
        curves.push({ key, panel, ys, f });
      } catch (e) {
        setStatus("evaluation failed: " + e.message, true);
      }
    }
    let vmax = 0;
    for (const c of curves) for (const y of c.ys) if (isFinite(y)) vmax = Math.max(vmax, y);
    if (!(vmax > 0)) vmax = 1;
    const radius = (y) => {
      if (!logScale) return R * y / vmax;
      if (y <= 0) return 0;
      return R * Math.max(0, 1 + Math.log10(y / vmax) / 4);
    };
    // grid
    ctx.lineWidth = 1;
    ctx.strokeStyle = "#e3e3e3";
    ctx.fillStyle = "#999";
    ctx.font = "11px system-ui, sans-serif";
    for (const fr of [0.25, 0.5, 0.75, 1]) {
      ctx.beginPath(); ctx.arc(cx, cy, R * fr, Math.PI, 2 * Math.PI); ctx.stroke();
    }
    for (let d = -90; d <= 90; d += 15) {
      const a = d * Math.PI / 180;
      ctx.beginPath(); ctx.moveTo(cx, cy); ctx.lineTo(cx + R * Math.sin(a), cy - R * Math.cos(a)); ctx.stroke();
      if (d % 30 === 0) ctx.fillText(`${d}°`, cx + (R + 4) * Math.sin(a) - 9, cy - (R + 6) * Math.cos(a) + 3);
    }
    ctx.strokeStyle = "#999";
    ctx.beginPath(); ctx.moveTo(cx - R - 10, cy); ctx.lineTo(cx + R + 10, cy); ctx.stroke();
    // incident and mirror directions
    const ti = dirs.ti;
    ctx.setLineDash([4, 4]);
    ctx.strokeStyle = "#bbb";
    ctx.beginPath(); ctx.moveTo(cx, cy); ctx.lineTo(cx + R * Math.sin(ti), cy - R * Math.cos(ti)); ctx.stroke();
    ctx.setLineDash([]);
    ctx.strokeStyle = "#e8a317"; ctx.lineWidth = 2;
    const lx = cx - R * Math.sin(ti), ly = cy - R * Math.cos(ti);
    ctx.beginPath(); ctx.moveTo(lx, ly); ctx.lineTo(cx, cy); ctx.stroke();
    const ang = Math.atan2(cy - ly, cx - lx);
    ctx.beginPath(); ctx.moveTo(cx, cy);
    ctx.lineTo(cx - 10 * Math.cos(ang - 0.35), cy - 10 * Math.sin(ang - 0.35));
    ctx.lineTo(cx - 10 * Math.cos(ang + 0.35), cy - 10 * Math.sin(ang + 0.35));
    ctx.closePath(); ctx.fillStyle = "#e8a317"; ctx.fill();
    // curves
    const css = getComputedStyle(document.documentElement);
    for (const c of curves) {
      ctx.strokeStyle = css.getPropertyValue(c.key === "main" ? "--main" : "--compare").trim();
      ctx.lineWidth = 2;
      ctx.setLineDash(c.key === "main" ? [] : [6, 4]);
      ctx.beginPath();
      dirs.angles.forEach((a, k) => {
        const r = radius(c.ys[k]);
        const x = cx + r * Math.sin(a), y = cy - r * Math.cos(a);
        if (k === 0) ctx.moveTo(x, y); else ctx.lineTo(x, y);
      });
      ctx.stroke();
    }
    ctx.setLineDash([]);
    ctx.fillStyle = "#555";
    ctx.fillText(`outer ring: ${fmt(vmax)}${logScale ? " (4 decades)" : ""}  ·  light at ${fmt(num("theta-i"))}°`, 8, 14);
    // read-out: the value in the mirror direction
    const parts = curves.map((c) => {
      const k = Math.round((dirs.ti * 180 / Math.PI + 89.9) / 179.8 * (NPOLAR - 1));
      const f = [0, 1, 2].map((i) => fmt(c.f[3 * k + i]));
      return `${c.panel.model}: f_r(mirror) = [${f.join(", ")}] /sr`;
    });
    $("#readout").textContent = parts.join("   ·   ");
  }

  function draw() {
    if (!gl) return;
    for (const id of ["light-theta", "light-phi", "theta-i", "plane-phi"]) $("#" + id + "-out").textContent = fmt(num(id)) + "°";
    $("#exposure-out").textContent = num("exposure").toFixed(1) + " EV";
    drawSphere();
    drawPolar();
    status.frames += 1;
  }

  // ------------------------------------------------------------------------
  // start-up
  // ------------------------------------------------------------------------
  async function crossCheck(name, params) {
    // a handful of direction pairs: max relative difference GPU vs numpy
    const wi = [], wo = [];
    for (const [a, b, c, d] of [[10, 0, 20, 180], [45, 30, 45, 210], [60, 90, 30, 270], [30, 10, 70, 200], [80, 0, 80, 180]]) {
      const r = Math.PI / 180;
      wi.push([Math.sin(a * r) * Math.cos(b * r), Math.sin(a * r) * Math.sin(b * r), Math.cos(a * r)]);
      wo.push([Math.sin(c * r) * Math.cos(d * r), Math.sin(c * r) * Math.sin(d * r), Math.cos(c * r)]);
    }
    const g = evaluateGPU(name, params, wi, wo);
    const n = await evaluateNumpy(name, params, wi, wo);
    let m = 0;
    for (let k = 0; k < g.length; k++) m = Math.max(m, Math.abs(g[k] - n[k]) / Math.max(Math.abs(n[k]), 1e-6));
    return m;
  }

  async function start() {
    const canvas = $("#sphere");
    gl = canvas.getContext("webgl2", { antialias: false, preserveDrawingBuffer: true });
    if (!gl) {
      status.error = "WebGL 2 is not available in this browser";
      setStatus(status.error, true);
      status.ready = true;
      return;
    }
    status.webgl2 = true;
    status.floatTargets = !!gl.getExtension("EXT_color_buffer_float");
    status.renderer = gl.getParameter(gl.RENDERER);
    const r = await fetch("/api/models");
    if (!r.ok) throw new Error("GET /api/models failed: " + r.status);
    const list = (await r.json()).models;
    const sources = await Promise.all(list.map(async (m) => {
      if (!m.glsl) return null;
      const s = await fetch("/api/shader/" + encodeURIComponent(m.name));
      return s.ok ? s.text() : null;
    }));
    list.forEach((m, i) => {
      modelInfo[m.name] = m;
      const src = sources[i];
      const st = { ok: false, error: null, sphere: false, eval: false };
      status.models[m.name] = st;
      if (src === null) { st.error = "no GLSL source"; return; }
      const P = {};
      try {
        P.sphere = compileProgram(src + SPHERE_MAIN);
        st.sphere = true;
        P.sphereUniforms = uniformLocations(P.sphere, m);
        P.sphereScene = {};
        for (const k of ["viewport", "light", "scale", "tangent", "background"]) P.sphereScene[k] = gl.getUniformLocation(P.sphere, "bkw_" + k);
        P.eval = compileProgram(src + EVAL_MAIN);
        st.eval = true;
        P.evalUniforms = uniformLocations(P.eval, m);
        P.evalSamplers = { wi: gl.getUniformLocation(P.eval, "bkw_wi"), wo: gl.getUniformLocation(P.eval, "bkw_wo") };
        st.ok = true;
      } catch (e) {
        st.error = e.message.split("\n")[0];
        console.error(`brdfkit: model ${m.name}: ${e.message}`);
      }
      programs[m.name] = P;
    });
    for (const key of ["main", "compare"]) {
      const sel = $("#model-" + key);
      for (const m of list) {
        const label = m.name + (status.models[m.name].ok ? "" : " (shader error)");
        sel.append(el("option", { value: m.name, text: label }));
      }
    }
    panels.main = new Panel("panel-main", false);
    panels.compare = new Panel("panel-compare", true);
    const params = new URLSearchParams(location.search);
    const first = params.get("model") && modelInfo[params.get("model")] ? params.get("model")
      : (modelInfo["microfacet"] ? "microfacet" : list[0].name);
    panels.main.setModel(first);
    const cmp = params.get("compare");
    panels.compare.setModel(cmp && modelInfo[cmp] ? cmp : "");
    for (const id of sceneInputs) {
      $("#" + id).addEventListener("input", scheduleDraw);
      $("#" + id).addEventListener("change", scheduleDraw);
    }
    $("#crosscheck").addEventListener("click", async () => {
      const out = $("#crosscheck-out");
      out.textContent = "…";
      try {
        const parts = [];
        for (const p of activePanels()) parts.push(`${p.model}: max rel. diff ${fmt(await crossCheck(p.model, p.params()))}`);
        out.textContent = parts.join("; ");
      } catch (e) { out.textContent = "failed: " + e.message; }
    });
    const bad = Object.entries(status.models).filter(([, s]) => !s.ok).map(([n]) => n);
    setStatus(`${list.length} models, ${bad.length ? "shader errors: " + bad.join(", ") : "all shaders compiled"} · ${status.renderer}`
      + (status.floatTargets ? "" : " · no float render targets"), bad.length > 0);
    draw();
    status.ready = true;
  }

  // a small API for scripts and tests
  window.brdfkit = {
    evaluate: (name, params, wi, wo) => Array.from(evaluateGPU(name, params, wi, wo)),
    evaluateNumpy: async (name, params, wi, wo) => Array.from(await evaluateNumpy(name, params, wi, wo)),
    crossCheck,
    panels,
    redraw: () => draw(),
  };

  start().catch((e) => {
    status.error = String(e && e.message || e);
    setStatus("start-up failed: " + status.error, true);
    status.ready = true;
  });
})();
