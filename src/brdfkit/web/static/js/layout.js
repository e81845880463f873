// The views and the two panes that show them (tabs; a view lives in one pane at a time), the
// draw loop (a change redraws the panes on the next animation frame, or only the view it
// affects), and the PNG / CSV exports.

import * as store from "./store.js";
import { $, $$, canvasOf, download, el, showError } from "./dom.js";
import { gl } from "./gl.js";
import { updateOutputs } from "./settings.js";
import { drawAlbedo } from "./views/albedo.js";
import { drawHalfDiffPlot, drawThetaV } from "./views/curves.js";
import { clearIblPending, iblPending } from "./views/ibl.js";
import { drawLobe3D } from "./views/lobe3d.js";
import { drawObject } from "./views/object.js";
import { drawPolar } from "./views/polar.js";
import { drawSlice, sliceCSV } from "./views/slice.js";
import { drawSphere } from "./views/sphere.js";

export const VIEWS = ["lobe3d", "polar", "theta_h", "theta_d", "theta_v", "albedo", "sphere", "slice", "object"];
const TITLES = { lobe3d: "3D lobe", polar: "polar", theta_h: "θh", theta_d: "θd", theta_v: "θv", albedo: "albedo",
  sphere: "lit sphere", slice: "image slice", object: "lit object" };
const DRAW = {
  lobe3d: drawLobe3D, polar: drawPolar, theta_h: () => drawHalfDiffPlot("theta_h"), theta_d: () => drawHalfDiffPlot("theta_d"),
  theta_v: drawThetaV, albedo: drawAlbedo, sphere: () => drawSphere(), slice: drawSlice, object: () => drawObject(),
};
const viewNodes = {};

/** Export buttons on every view, the tabs of both panes, and the panes' first views. */
export function setupViews() {
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
      b.addEventListener("click", () => { showView(name, i); store.changed(); });
      nav.append(b);
    }
  }
  const panes = store.get("panes");
  showView(panes[0], 0);
  showView(panes[1], 1);
}

/** Show view `name` in pane 0 or 1 (the view shown there moves to the other pane if `name` was there). */
export function showView(name, pane) {
  if (!VIEWS.includes(name)) throw new Error(`unknown view '${name}'; views: ${VIEWS.join(", ")}`);
  const panes = store.update("panes", (p) => {
    const other = 1 - pane;
    if (p[other] === name) p[other] = p[pane];  // swap: a view lives in one pane at a time
    p[pane] = name;
    return p;
  });
  for (let i = 0; i < 2; i++) {
    const body = $(`#pane-${i} .pane-body`);
    const node = viewNodes[panes[i]];
    if (node.parentNode !== body) { body.textContent = ""; body.append(node); }
    for (const b of $$(`#pane-${i} .tabs button`)) b.classList.toggle("active", b.dataset.view === panes[i]);
  }
  for (const v of VIEWS) if (!panes.includes(v)) $("#view-store").append(viewNodes[v]);
}

/** Draw one view now (shown or not) and count it in window.brdfkitStatus.drawn. */
export function drawView(name) {
  if (!gl) return;
  DRAW[name]();
  const drawn = store.get("status").drawn;
  drawn[name] = (drawn[name] || 0) + 1;
}

/** Draw the panes' views. onlyObject: the progressive environment-lit object's next pass;
 * views: a Set of the views to draw, or null for all shown. */
export function draw(onlyObject, views) {
  if (!gl) return;
  updateOutputs();
  const panes = store.get("panes");
  const list = panes.filter((v) => (views ? views.has(v) : (!onlyObject || v === "object")));
  if (list.includes("object")) clearIblPending();  // (else a progressive object keeps its next pass)
  for (const v of list) drawView(v);
  store.get("status").frames += 1;
  if (iblPending() && panes.includes("object")) {  // progressive: another pass of the lit object next frame
    requestAnimationFrame(() => { if (!drawPending) draw(true); });
  }
}

// the next frame draws every pane, or (drawOnly, a Set) only the views asked for
let drawPending = false, drawOnly = null;

/** Draw on the next animation frame: every pane, or only the view `only` (merged with earlier asks). */
export function scheduleDraw(only) {
  if (!drawPending) drawOnly = only ? new Set([only]) : null;
  else if (drawOnly) { if (only) drawOnly.add(only); else drawOnly = null; }
  if (drawPending) return;
  drawPending = true;
  requestAnimationFrame(() => { const o = drawOnly; drawPending = false; drawOnly = null; draw(false, o); });
}

function exportPNG(name) {
  drawView(name);
  canvasOf(name).toBlob((b) => download(`brdfkit-${name}.png`, b), "image/png");
}

/** A plot view's numbers as CSV text (the slice: f_r on a 2° grid of θh, θd). */
export function csvText(name) {
  drawView(name);
  if (name === "slice") store.update("viewData", (d) => { d.sliceCSV = sliceCSV(); });
  const viewData = store.get("viewData");
  const d = name === "slice" ? viewData.sliceCSV : viewData[name];
  if (!d) throw new Error(`view '${name}' has no numbers to export`);
  return [d.header.join(",")].concat(d.rows.map((r) => r.map((x) => (typeof x === "number" ? +x.toPrecision(8) : x)).join(","))).join("\n") + "\n";
}

function exportCSV(name) {
  try { download(`brdfkit-${name}.csv`, new Blob([csvText(name)], { type: "text/csv" })); } catch (e) { showError(e); }
}
