// The lit object: a mesh drawn by the renderer's own pipeline GLSL (a BRDF under one light, or
// the OpenGL fixed-function model), or lit by an environment (./ibl.js).

import * as store from "../store.js";
import { $, canvasOf, el } from "../dom.js";
import { gl, glCanvas, glSize, blit, U } from "../gl.js";
import { DEG, objectMatrices } from "../numbers.js";
import { getSetting, num } from "../settings.js";
import { bindMaterial, evaluateGPU, getProgram, intConstants, sourceKey } from "../brdfs.js";
import { visiblePanels } from "../panels.js";
import { currentMesh } from "./meshes.js";
import { clearIblImage, iblImage, renderObjectIBL } from "./ibl.js";
import { reportDrawError } from "./plot.js";

export function refreshObjectMaterials() {
  const s = $("#obj-material");
  if (!s) return;
  const cur = s.value;
  s.textContent = "";
  s.append(el("option", { value: "brdf:0", text: "BRDF: the first visible one" }));
  for (let i = 1; i < 8; i++) s.append(el("option", { value: `brdf:${i}`, text: `BRDF: visible number ${i + 1}` }));
  const g = el("optgroup", { label: "OpenGL fixed function (the lecture's table)" });
  for (const m of Object.keys(store.get("openglTable") ? store.get("openglTable").materials : {})) g.append(el("option", { value: "gl:" + m, text: "OpenGL: " + m }));
  s.append(g);
  s.value = cur || "brdf:0";
  if (!s.value) s.value = "brdf:0";
}

// the list of BRDFs changed: so did the material choices
store.subscribe("catalog", refreshObjectMaterials);

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
  const M = objectMatrices(store.get("orbit").object, w, h);
  gl.uniformMatrix4fv(U(prog, "bkr_modelview"), false, M.mv);
  gl.uniformMatrix4fv(U(prog, "bkr_projection"), false, M.proj);
  gl.uniformMatrix3fv(U(prog, "bkr_normal_matrix"), false, M.nm);
  // one light, eye space (OpenGL's Light fields)
  const th = num("obj-light-theta") * DEG, ph = num("obj-light-phi") * DEG;
  const Ld = [Math.sin(th) * Math.cos(ph), Math.sin(th) * Math.sin(ph), Math.cos(th)]; // θ from the view axis
  const point = getSetting("obj-light-type") === "point";
  const dist = num("obj-light-dist"), camDist = 3.4 / store.get("orbit").object.zoom;
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
    const m = store.get("openglTable").materials[matSel.slice(3)];
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

export function drawObject(canvasArg) {
  const canvas = canvasArg || canvasOf("object");
  const ctx = canvas.getContext("2d");
  let note = "";
  clearIblImage();
  try { note = renderObject(canvas.width, canvas.height); } catch (e) { reportDrawError(e); note = "failed: " + e.message; }
  const image = iblImage();
  if (image) ctx.putImageData(image, 0, 0);
  else blit(ctx, canvas.width, canvas.height);
  $("#object-note").textContent = note;
}
