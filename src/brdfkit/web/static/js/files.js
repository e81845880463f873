// Dropped or opened files: a MERL .binary (a table in a 3D texture), a Disney .brdf (its GLSL
// from the server) and an .obj mesh. Their bytes survive a reload: they are kept in IndexedDB
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
  store.update("merlTables", (tables) => {
    if (tables[label]) gl.deleteTexture(tables[label].texture);
    tables[label] = { texture: tex };
  });
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

const FILE_KINDS = [[/\.(binary|bin)$/i, loadMerlFile], [/\.brdf$/i, loadBrdfFile], [/\.obj$/i, loadObjFile]];

/** The loader of a file name (MERL, .brdf, .obj), or null. */
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
