// Dropped or opened files: a MERL .binary (a table in a 3D texture), an RGL .bsdf or a .bin
// (UTIA or MERL, told by the server from its content: the textures of its GLSL twin, rgl.glsl,
// utia.glsl or measured.glsl), a Disney .brdf (its GLSL from the server) and an .obj mesh. Their bytes survive a reload: they are kept in IndexedDB
// under their SHA-256, the state (URL, saved view) names them ({name, sha256}); a state naming
// a file this browser no longer holds is an error on the page.

import * as store from "./store.js";
import { $, showError } from "./dom.js";
import { gl } from "./gl.js";
import { fetchJSON, fetchText } from "./net.js";
import { dropPrograms } from "./brdfs.js";
import { getSetting } from "./settings.js";
import { meshBuffers } from "./views/meshes.js";

async function loadMerlFile(file) {
  const buf = await file.arrayBuffer();
  const r = await fetch("/api/merl", { method: "POST", body: buf, headers: { "Content-Type": "application/octet-stream" } });
  if (!r.ok) { const b = await r.json().catch(() => ({ error: r.statusText })); throw new Error(`${file.name}: ${b.error}`); }
  const texels = new Float32Array(await r.arrayBuffer());
  if (texels.length !== 90 * 90 * 180 * 4) throw new Error(`${file.name}: unexpected table size from the server`);
  const sources = store.get("sources");
  if (sources.__merl === undefined) sources.__merl = await fetchText("/api/measured/shader");
  const tex = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_3D, tex);
  for (const p of [gl.TEXTURE_MIN_FILTER, gl.TEXTURE_MAG_FILTER]) gl.texParameteri(gl.TEXTURE_3D, p, gl.NEAREST);
  for (const p of [gl.TEXTURE_WRAP_S, gl.TEXTURE_WRAP_T, gl.TEXTURE_WRAP_R]) gl.texParameteri(gl.TEXTURE_3D, p, gl.CLAMP_TO_EDGE);
  gl.texImage3D(gl.TEXTURE_3D, 0, gl.RGBA32F, 180, 90, 90, 0, gl.RGBA, gl.FLOAT, texels);
  const label = "file:" + file.name.replace(/\.(binary|bin)$/, "");
  forgetTables(label);
  store.update("merlTables", (tables) => { tables[label] = { texture: tex }; });
  store.emit("catalog");
  return label;
}

/** Drop a loaded table file's label from every kind of table (a file loaded again, maybe as another format). */
function forgetTables(label) {
  store.update("merlTables", (tables) => {
    if (tables[label]) { gl.deleteTexture(tables[label].texture); delete tables[label]; }
  });
  store.update("tableFiles", (files) => {
    if (files[label]) { for (const t of files[label].textures) gl.deleteTexture(t.texture); delete files[label]; }
  });
}

/** The header and the textures of /api/measured/file's answer (brdfkit.render.tables.pack). */
function unpackTables(buf, fileName) {
  const n = new DataView(buf).getUint32(0, true);
  const head = JSON.parse(new TextDecoder().decode(new Uint8Array(buf, 4, n)));
  if (4 + n + head.bytes !== buf.byteLength) throw new Error(`${fileName}: unexpected table size from the server`);
  const max3d = gl.getParameter(gl.MAX_3D_TEXTURE_SIZE), max2d = gl.getParameter(gl.MAX_TEXTURE_SIZE);
  const textures = head.textures.map((t) => {
    const max = t.dims === 3 ? max3d : max2d;
    if (t.size.some((s) => s > max)) throw new Error(`${fileName}: a ${t.size.join("×")} table is larger than this WebGL allows (${max} per side)`);
    const count = t.size.reduce((a, b) => a * b, 1) * t.components;
    return Object.assign({}, t, { data: new Float32Array(buf, 4 + n + t.offset, count) });
  });
  return { head, textures };
}

function tableTexture(t) {
  const target = t.dims === 3 ? gl.TEXTURE_3D : gl.TEXTURE_2D;
  const [ifmt, fmt] = t.components === 1 ? [gl.R32F, gl.RED] : [gl.RGBA32F, gl.RGBA];
  const tex = gl.createTexture();
  gl.bindTexture(target, tex);
  for (const p of [gl.TEXTURE_MIN_FILTER, gl.TEXTURE_MAG_FILTER]) gl.texParameteri(target, p, gl.NEAREST);
  for (const p of [gl.TEXTURE_WRAP_S, gl.TEXTURE_WRAP_T, gl.TEXTURE_WRAP_R]) gl.texParameteri(target, p, gl.CLAMP_TO_EDGE);
  gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
  if (t.dims === 3) gl.texImage3D(target, 0, ifmt, t.size[0], t.size[1], t.size[2], 0, fmt, gl.FLOAT, t.data);
  else gl.texImage2D(target, 0, ifmt, t.size[0], t.size[1], 0, fmt, gl.FLOAT, t.data);
  gl.pixelStorei(gl.UNPACK_ALIGNMENT, 4);
  return { uniform: t.uniform, unit: t.unit, target, texture: tex };
}

async function loadTableFile(file) {
  const r = await fetch("/api/measured/file?name=" + encodeURIComponent(file.name),
    { method: "POST", body: await file.arrayBuffer(), headers: { "Content-Type": "application/octet-stream" } });
  if (!r.ok) { const b = await r.json().catch(() => ({ error: r.statusText })); throw new Error(b.error || `${file.name}: ${r.statusText}`); }
  const { head, textures } = unpackTables(await r.arrayBuffer(), file.name);
  const key = "__table:" + head.format;
  const sources = store.get("sources");
  if (sources[key] === undefined) sources[key] = await fetchText("/api/measured/shader?format=" + head.format);
  const label = "file:" + file.name.replace(/\.(bsdf|bin)$/i, "");
  forgetTables(label);
  const made = textures.map(tableTexture);
  const info = { name: label, title: head.title, reference: "", params: [], isotropic: head.isotropic };
  store.update("tableFiles", (files) => { files[label] = { format: head.format, key, textures: made, ints: head.ints, info }; });
  store.emit("catalog");
  return label;
}

async function loadBrdfFile(file) {
  const text = await file.text();
  const r = await fetch("/api/brdf?name=" + encodeURIComponent(file.name), { method: "POST", body: text, headers: { "Content-Type": "text/plain" } });
  const body = await r.json().catch(() => ({ error: r.statusText }));
  if (!r.ok) throw new Error(`${file.name}: ${r.status === 404 ? "loading .brdf files is not available in this build" : body.error}`);
  const label = "brdf:" + file.name.replace(/\.brdf$/, "");
  const key = "__brdf:" + label;
  store.update("sources", (sources) => { sources[key] = body.glsl; });
  dropPrograms(key);  // a file loaded again
  const info = Object.assign({ title: "Disney BRDF Explorer file", reference: "" }, body.info, { name: label });
  store.update("brdfFiles", (files) => { files[label] = { info, key }; });
  store.emit("catalog");
  return label;
}

async function loadObjFile(file) {
  const m = await fetchJSON("/api/mesh", { method: "POST", body: await file.arrayBuffer() });
  m.name = file.name;
  store.set("uploadedMesh", meshBuffers(m));
  $("#obj-mesh option[value=uploaded]").disabled = false;
  return "obj";
}

const FILE_KINDS = [[/\.binary$/i, loadMerlFile], [/\.(bsdf|bin)$/i, loadTableFile], [/\.brdf$/i, loadBrdfFile],
  [/\.obj$/i, loadObjFile]];

/** The loader of a file name (MERL, RGL, UTIA, .brdf, .obj), or null. */
export const fileLoader = (name) => (FILE_KINDS.find(([re]) => re.test(name)) || [null, null])[1];

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

/** Load a dropped file's bytes into the page and keep them; -> the label of what it made. */
export async function loadAndKeep(name, bytes) {
  const label = await fileLoader(name)(new File([bytes], name));
  try {
    const sha256 = await sha256Hex(bytes);
    await idbRequest((await idbStore("readwrite")).put({ name, bytes }, sha256));
    store.update("loadedFiles", (files) => { files[label] = { name, sha256 }; });
  } catch (e) {
    store.update("loadedFiles", (files) => { delete files[label]; });
    showError(`${name}: loaded, but not kept for a reload (${e.message})`);
  }
  return label;
}

/** The files a state names, back from IndexedDB (a missing one: an error on the page). */
export async function restoreFiles(files, origin) {
  if (!Array.isArray(files)) { showError(`${origin}: files must be a list of {"name", "sha256"}`); return; }
  for (const f of files) {
    const ok = f && typeof f.name === "string" && typeof f.sha256 === "string" && /^[0-9a-f]{64}$/.test(f.sha256);
    if (!ok || !fileLoader(f.name)) { showError(`${origin}: bad files entry ${JSON.stringify(f)}`); continue; }
    if (Object.values(store.get("loadedFiles")).some((g) => g.sha256 === f.sha256 && g.name === f.name)) continue;
    try {
      const rec = await idbRequest((await idbStore("readonly")).get(f.sha256));
      if (!rec) throw new Error("it is not stored in this browser (IndexedDB was cleared, or another browser or profile): drop the file again");
      const label = await fileLoader(f.name)(new File([rec.bytes], f.name));
      store.update("loadedFiles", (kept) => { kept[label] = { name: f.name, sha256: f.sha256 }; });
    } catch (e) { showError(`${origin}: dropped file '${f.name}' (sha256 ${f.sha256.slice(0, 12)}…): ${e.message}`); }
  }
}

/** The kept files the current state uses (its BRDFs' and the uploaded mesh's). */
export function stateFiles(models) {
  return Object.entries(store.get("loadedFiles"))
    .filter(([label]) => (label === "obj" ? getSetting("obj-mesh") === "uploaded" : models.includes(label)))
    .map(([, f]) => ({ name: f.name, sha256: f.sha256 }));
}
