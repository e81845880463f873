// The BRDF panels: one per BRDF shown, each with its model, its parameter controls and its
// colour. The list lives in the store ("panels"); a panel reports a change with store.changed().

import * as store from "./store.js";
import { $, el, showError } from "./dom.js";
import { COLORS, STEPS, effectiveParams, fmt, sliderMap, srgbEncode, srgbToLinear } from "./numbers.js";
import { ensureLoaded, infoOf } from "./brdfs.js";

let nextPanelId = 0;

/** Fill a model <select>: the analytic models, the loaded files, the measured materials. */
function modelOptions(select, current) {
  select.textContent = "";
  const status = store.get("status");
  const g1 = el("optgroup", { label: "analytic models" });
  for (const name of Object.keys(store.get("modelInfo"))) {
    const st = status.models[name];
    g1.append(el("option", { value: name, text: name + (st && !st.ok ? " (shader error)" : "") }));
  }
  select.append(g1);
  const loaded = Object.keys(store.get("merlTables")).concat(Object.keys(store.get("tableFiles")), Object.keys(store.get("brdfFiles")));
  if (loaded.length) {
    const g = el("optgroup", { label: "loaded files" });
    for (const n of loaded) g.append(el("option", { value: n, text: n }));
    select.append(g);
  }
  const measured = store.get("measuredNames");
  const g2 = el("optgroup", { label: `measured (${measured.length})` });
  for (const n of measured) g2.append(el("option", { value: n, text: n }));
  select.append(g2);
  if (current) select.value = current;
}

// a BRDF was loaded from a file: every panel's list shows it
store.subscribe("catalog", () => { for (const p of store.get("panels")) modelOptions(p.select, p.model); });

export class Panel {
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
    this.visibleBox.addEventListener("change", () => { this.visible = this.visibleBox.checked; store.changed(); });
    solo.addEventListener("click", () => { for (const p of store.get("panels")) p.setVisible(p === this); store.changed(); });
    remove.addEventListener("click", () => removePanel(this));
    reset.addEventListener("click", () => { this.setModel(this.model); store.changed(); });
  }

  setVisible(v) { this.visible = !!v; this.visibleBox.checked = this.visible; }

  async setModelAsync(name, params) {
    try {
      await ensureLoaded(name);
      this.setModel(name, params);
    } catch (e) { showError(e); this.select.value = this.model || ""; }
    store.changed();
  }

  // synchronous: the BRDF must be loaded (ensureLoaded)
  setModel(name, params) {
    this.model = name;
    this.paramsBox.textContent = "";
    this.controls = {};
    modelOptions(this.select, name);
    const info = infoOf(name);
    const st = store.get("status").models[name];
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
    const onchange = () => { this.onChange(p.name); store.changed(); };
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
        c.picker.value = "#" + norm.map((x) => Math.round(srgbEncode(Math.min(1, Math.max(0, x))) * 255)
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

/** A new panel for `name` (loaded: see ensureLoaded) at the end of the list, in the first free colour. */
export function addPanel(name, params) {
  const panels = store.get("panels");
  const used = new Set(panels.map((p) => p.color));
  const color = COLORS.find((c) => !used.has(c)) || COLORS[panels.length % COLORS.length];
  const p = new Panel(color);
  store.update("panels", (list) => list.push(p));
  $("#brdf-list").append(p.root);
  p.setModel(name, params);
  return p;
}

function removePanel(p) {
  const panels = store.get("panels");
  if (panels.length <= 1) { showError("the last BRDF cannot be removed"); return; }
  store.update("panels", (list) => list.splice(list.indexOf(p), 1));
  p.root.remove();
  store.changed();
}

/** Remove every panel (the list object stays the same: window.brdfkit.panels is it). */
export function clearPanels() {
  store.update("panels", (list) => { for (const p of list) p.root.remove(); list.length = 0; });
}

export const visiblePanels = () => store.get("panels").filter((p) => p.visible && p.model);
