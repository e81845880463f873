// brdfkit explorer: native ES modules + WebGL 2, no build step, nothing fetched from outside.
//
// Every BRDF is evaluated in one WebGL 2 context (./gl.js) by its own GLSL file (the renderer's
// shaders, served by /api/shader/<model>; measured materials by render/shaders/nbrdf.glsl
// (Neural-BRDF networks) or measured.glsl (a MERL table in a 3D texture)), appended with a small
// main per use (./shaders.js):
//   * EVAL: brdf() for direction pairs (./brdfs.js: every plot, the albedo quadrature, window.brdfkit.eval);
//   * SPHERE: a lit sphere, ray-cast per pixel; SLICE: the θh × θd image;
//   * the lit object: the renderer's own pipeline (pipeline_lights/vertex/fragment.glsl,
//     pipeline_brdf.glsl or opengl_fixed.glsl) assembled as brdfkit.render.renderer does.
// The shared state lives in ./store.js; each view is a module of ./views/; ./urlstate.js and
// ./apply.js carry the state in the URL. This module starts the page and defines its API for
// scripts and tests (SPEC.md: window.brdfkit.eval, views, state); window.brdfkitStatus reports
// readiness and per-model compile errors.

import * as store from "./store.js";
import { $, canvasOf, clearErrors, download, el, errors, setStatus, showError } from "./dom.js";
import { gl, initGL } from "./gl.js";
import { fetchJSON, fetchText } from "./net.js";
import { flat3 } from "./numbers.js";
import { PIPELINE_FILES } from "./shaders.js";
import { ensureLoaded, evaluateGPU, evaluateNumpy, getProgram, kindOf, validated } from "./brdfs.js";
import { fileLoader, loadAndKeep } from "./files.js";
import { addPanel, clearPanels } from "./panels.js";
import { resetSettings, setSetting, setupSettings, updateOutputs } from "./settings.js";
import { flushURL, getState, updateURL } from "./urlstate.js";
import { applyState, loadURL } from "./apply.js";
import { VIEWS, csvText, draw, drawView, scheduleDraw, setupViews, showView } from "./layout.js";
import { setupMouse } from "./mouse.js";
import { iblDone } from "./views/ibl.js";
import { meshReady } from "./views/meshes.js";
import { drawObject, refreshObjectMaterials } from "./views/object.js";
import { drawSphere } from "./views/sphere.js";

const status = store.get("status");
window.brdfkitStatus = status;

// a change of state: the numbers by the sliders, the URL, and a redraw (of the one view it affects, or all)
store.subscribe("changed", (only) => { updateOutputs(); updateURL(); scheduleDraw(only); });
store.subscribe("draw", (only) => scheduleDraw(only));

const defaultModel = () => {
  const models = store.get("modelInfo");
  return models.microfacet ? "microfacet" : Object.keys(models)[0];
};

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
        if (!store.get("panes").includes("object")) showView("object", 1);
      } else addPanel(label, {});
      store.changed();
    } else {
      throw new Error(`${file.name}: unknown file type; drop a .json view, a MERL .binary, an RGL .bsdf, a UTIA .bin, a .brdf or an .obj`);
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
async function loadCatalog() {
  const [list, measured, gltab] = await Promise.all([
    fetchJSON("/api/models").then((b) => b.models), fetchJSON("/api/measured").then((b) => b.materials), fetchJSON("/api/opengl")]);
  store.set("measuredNames", measured);
  store.set("openglTable", gltab);
  const shaderFiles = store.get("shaderFiles");
  const texts = await Promise.all(PIPELINE_FILES.map((f) => fetchText("/api/glsl?file=" + f)));
  PIPELINE_FILES.forEach((f, i) => { shaderFiles[f] = texts[i]; });
  try {  // image-based lighting: the renderer's ibl*.glsl and the built-in maps
    const [a, b, envs] = await Promise.all([fetchText("/api/glsl?file=ibl_sampling.glsl"), fetchText("/api/glsl?file=ibl.glsl"),
      fetchJSON("/api/envs")]);
    shaderFiles["ibl_sampling.glsl"] = a; shaderFiles["ibl.glsl"] = b;
    for (const [name, doc] of Object.entries(envs.environments)) $("#obj-lighting").append(el("option", { value: "env:" + name, text: "environment: " + name, title: doc }));
  } catch (e) { /* a server without image-based lighting: point lights only */ }
  const srcs = await Promise.all(list.map((m) => (m.glsl ? fetchText("/api/shader/" + encodeURIComponent(m.name)).catch(() => null) : null)));
  const modelInfo = store.get("modelInfo"), sources = store.get("sources");
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
  return list;
}

async function start() {
  if (!initGL()) {
    status.error = "WebGL 2 is not available in this browser";
    setStatus(status.error, true);
    status.ready = true;
    return;
  }
  status.webgl2 = true;
  status.floatTargets = !!gl.getExtension("EXT_color_buffer_float");
  status.renderer = gl.getParameter(gl.RENDERER);
  const list = await loadCatalog();
  setupViews();
  setupMouse();
  setupFiles();
  refreshObjectMaterials();
  setupSettings();
  $("#add-brdf").addEventListener("click", () => {
    const taken = new Set(store.get("panels").map((p) => p.model));
    const names = Object.keys(store.get("modelInfo"));
    addPanel(names.find((n) => !taken.has(n)) || names[0], {});
    store.changed();
  });
  $("#reset-all").addEventListener("click", () => resetAll());
  if (location.search) await loadURL(location.search);
  if (!store.get("panels").length) addPanel(defaultModel(), {});
  const bad = Object.entries(status.models).filter(([, s]) => !s.ok).map(([n]) => n);
  setStatus(`${list.length} models + ${store.get("measuredNames").length} measured, ${bad.length ? "shader errors: " + bad.join(", ") : "all shaders compiled"} · ${status.renderer}`
    + (status.floatTargets ? "" : " · no float render targets"), bad.length > 0);
  updateOutputs();
  draw();
  flushURL();
  status.ready = true;
}

function resetAll() {
  clearPanels();
  addPanel(defaultModel(), {});
  resetSettings();
  store.update("orbit", (orbit) => {
    Object.assign(orbit.lobe3d, store.ORBIT_DEFAULTS.lobe3d);
    Object.assign(orbit.object, store.ORBIT_DEFAULTS.object);
  });
  clearErrors();
  store.changed();
}

// ------------------------------------------------------------------------
// the page's API for scripts and tests (SPEC.md: eval, views, state)
// ------------------------------------------------------------------------
const validatedCache = new Set();

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
  data: (view) => { drawView(view); return store.get("viewData")[view] || null; },
  csv: (view) => csvText(view),
  canvas: (view) => canvasOf(view),
  panels: store.get("panels"),
  addBRDF: async (name, params) => { await ensureLoaded(name); const p = addPanel(name, params || {}); store.changed(); return p.id; },
  errors: () => errors(),
  redraw: () => draw(),
  openFile: (file) => openFile(file),
  meshReady: () => meshReady(),
  iblDone: () => iblDone(),
  // the older synchronous form: a flat [r, g, b, r, g, b, ...] for lists of directions (analytic models)
  evaluate: (name, params, wi, wo) => Array.from(evaluateGPU(name, params, flat3(wi), flat3(wo))),
  evaluateNumpy: async (name, params, wi, wo) => Array.from(await evaluateNumpy(name, params, wi, wo)),
  bench: (view, w, h, frames, budgetS) => bench(view, w, h, frames, budgetS),
};

// frames per second of one view drawn into a w x h canvas (gl.finish each frame):
// `frames` frames, or fewer (at least 3) once `budgetS` seconds have passed
function bench(view, w, h, frames, budgetS) {
  const c = document.createElement("canvas");
  c.width = w; c.height = h;
  const fn = view === "sphere" ? () => drawSphere(c) : () => drawObject(c);
  fn(); gl.finish();
  const t0 = performance.now();
  let n = 0;
  while (n < frames && (n < 3 || !budgetS || performance.now() - t0 < 1000 * budgetS)) { fn(); gl.finish(); n++; }
  const dt = (performance.now() - t0) / 1000;
  return { fps: n / dt, seconds: dt, frames: n, width: w, height: h };
}

start().catch((e) => {
  status.error = String(e && e.message || e);
  setStatus("start-up failed: " + status.error, true);
  status.ready = true;
});
