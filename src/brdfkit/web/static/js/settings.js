// The view settings: the global bar's and each view's controls in index.html, read and set by id.
// The controls themselves hold the values (their defaults are the store's `defaults`).

import * as store from "./store.js";
import { $, $$ } from "./dom.js";
import { fmt } from "./numbers.js";

export const SETTINGS = {  // id -> kind
  "theta-i": "num", "phi-i": "num", "theta-h": "num", "theta-d": "num", "phi-d": "num", exposure: "num",
  channel: "str", scale: "str", ndotl: "bool",
  "light-theta": "num", "light-phi": "num", tangent: "str", "albedo-method": "str",
  "obj-mesh": "str", "obj-tess": "num", "obj-lighting": "str", "obj-ibl-spp": "num", "obj-shading": "str", "obj-material": "str", "obj-light-type": "str",
  "obj-light-theta": "num", "obj-light-phi": "num", "obj-light-dist": "num", "obj-light-diffuse": "num",
  "obj-light-specular": "num", "obj-light-ambient": "num", "obj-scene-ambient": "num",
  "obj-att-c": "num", "obj-att-l": "num", "obj-att-q": "num", "obj-local-viewer": "bool",
};
export const SPHERE_ONLY = new Set(["light-theta", "light-phi", "tangent"]);  // settings only the lit sphere reads

export function num(id) { return parseFloat($("#" + id).value); }

export function getSetting(id) {
  const e = $("#" + id), k = SETTINGS[id];
  return k === "bool" ? e.checked : k === "num" ? parseFloat(e.value) : e.value;
}

/** Set a control; a value of the wrong type, out of range or not an option is a one-line Error. */
export function setSetting(id, v) {
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

/** Every setting's current value, by id. */
export function allSettings() {
  const view = {};
  for (const id of Object.keys(SETTINGS)) view[id] = getSetting(id);
  return view;
}

/** Remember index.html's values as the defaults; every control's input reports a change of state. */
export function setupSettings() {
  const defaults = store.get("defaults");
  for (const id of Object.keys(SETTINGS)) {
    defaults[id] = getSetting(id);
    const only = SPHERE_ONLY.has(id) ? "sphere" : null;
    $("#" + id).addEventListener("input", () => store.changed(only));
    $("#" + id).addEventListener("change", () => store.changed(only));
  }
}

/** Every setting back to its default. */
export function resetSettings() {
  for (const [k, v] of Object.entries(store.get("defaults"))) setSetting(k, v);
}

/** The numbers shown next to the sliders. */
export function updateOutputs() {
  for (const o of $$("output[for]")) {
    const id = o.getAttribute("for");
    const v = num(id);
    o.textContent = id === "exposure" ? v.toFixed(1) + " EV" : id === "obj-tess" || id === "obj-light-dist" ? fmt(v) : fmt(v) + "°";
  }
}
