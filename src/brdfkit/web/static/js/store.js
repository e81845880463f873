// The page's one state store: every piece of mutable state more than one module reads lives here,
// behind explicit get / set / update / subscribe. Modules never share a mutable variable directly.
//
// Keys (the value's shape):
//   status        window.brdfkitStatus: {ready, webgl2, floatTargets, renderer, models, error, frames, drawn}
//   modelInfo     analytic model name -> its /api/models row
//   measuredNames the built-in measured materials (["set/name", ...])
//   sources       GLSL source key -> text (model name, "__nbrdf", "__merl", "__table:<format>", "__brdf:<label>")
//   programs      program id -> WebGLProgram, or {error}
//   merlTables    loaded MERL label -> {texture}
//   tableFiles    loaded RGL/UTIA/.bin label -> {format, key, textures: [{uniform, unit, target, texture}], ints, info}
//   brdfFiles     loaded .brdf label -> {info, key}
//   shaderFiles   render/shaders file name -> text (the pipeline's files)
//   openglTable   /api/opengl (the fixed-function materials and light)
//   loadedFiles   what a dropped file made ("file:NAME", "brdf:NAME", "obj") -> {name, sha256}
//   uploadedMesh  the uploaded OBJ's GL buffers, or null
//   panels        the BRDF panels, in order (a list mutated in place: window.brdfkit.panels is it)
//   panes         the two views shown, [left, right]
//   orbit         {lobe3d: {yaw, pitch, zoom}, object: {...}}
//   defaults      view setting id -> its value in index.html
//   viewData      view -> its numbers for CSV and checks
//
// Events (subscribe(name, fn) like a key): "changed" (only: a view name or null) after any change
// of state, "draw" (only) to redraw without a state change, "catalog" when the list of BRDFs changes.

const values = new Map();
const listeners = new Map();

function initial() {
  const status = {
    ready: false, webgl2: false, floatTargets: false, renderer: null,
    models: {}, error: null, frames: 0,
    drawn: {},  // view -> how many times it was drawn (a setting redraws only the views it changes)
  };
  const orbit = { lobe3d: { yaw: -60, pitch: 25, zoom: 1.3 }, object: { yaw: 20, pitch: 15, zoom: 1 } };
  return {
    status, modelInfo: {}, measuredNames: [], sources: {}, programs: {}, merlTables: {}, tableFiles: {}, brdfFiles: {},
    shaderFiles: {}, openglTable: null, loadedFiles: {}, uploadedMesh: null, panels: [],
    panes: ["polar", "sphere"], orbit, defaults: {}, viewData: {},
  };
}
for (const [k, v] of Object.entries(initial())) values.set(k, v);

export const ORBIT_DEFAULTS = JSON.parse(JSON.stringify(values.get("orbit")));

function known(key) {
  if (!values.has(key)) throw new Error(`store: unknown key '${key}'`);
}

/** The value under `key` (objects are the live ones: mutate them through update()). */
export function get(key) {
  known(key);
  return values.get(key);
}

/** Replace the value under `key` and tell its subscribers. */
export function set(key, value) {
  known(key);
  values.set(key, value);
  notify(key, value);
}

/** Change the value under `key` in place (`fn(value)`), then tell its subscribers. */
export function update(key, fn) {
  known(key);
  const out = fn(values.get(key));
  notify(key, values.get(key));
  return out;
}

/** Call `fn(value)` whenever `key` is set or updated, or `fn(arg)` when the event `key` is emitted. */
export function subscribe(key, fn) {
  if (!listeners.has(key)) listeners.set(key, new Set());
  listeners.get(key).add(fn);
  return () => listeners.get(key).delete(fn);
}

/** Tell the subscribers of the event `name` (not a stored value). */
export function emit(name, arg) {
  notify(name, arg);
}

function notify(key, arg) {
  for (const fn of Array.from(listeners.get(key) || [])) fn(arg);
}

/** A change of state: only = the one view it affects (the lit sphere's light), else all. */
export const changed = (only) => emit("changed", typeof only === "string" ? only : null);
/** A redraw without a change of state (data arrived from the server). */
export const requestDraw = (only) => emit("draw", only || null);
