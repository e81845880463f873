// The lit object's meshes: built-ins from /api/mesh (cached per tessellation), or the uploaded OBJ
// (the store's "uploadedMesh"), as GL buffers.

import * as store from "../store.js";
import { showError } from "../dom.js";
import { gl } from "../gl.js";
import { fetchJSON } from "../net.js";
import { getSetting } from "../settings.js";

const meshCache = {};
let meshPending = null;

/** GL buffers of a /api/mesh answer {name, positions, normals, tangents, faces}. */
export function meshBuffers(m) {
  const mk = (data, target) => { const b = gl.createBuffer(); gl.bindBuffer(target, b); gl.bufferData(target, data, gl.STATIC_DRAW); return b; };
  return {
    name: m.name, n: m.faces.length, triangles: m.faces.length / 3, vertices: m.positions.length / 3,
    pos: mk(Float32Array.from(m.positions), gl.ARRAY_BUFFER), nor: mk(Float32Array.from(m.normals), gl.ARRAY_BUFFER),
    tan: mk(Float32Array.from(m.tangents), gl.ARRAY_BUFFER), idx: mk(Uint32Array.from(m.faces), gl.ELEMENT_ARRAY_BUFFER),
  };
}

/** The mesh the settings ask for, or null while it is being fetched (a redraw follows). */
export function currentMesh() {
  const name = getSetting("obj-mesh");
  if (name === "uploaded") return store.get("uploadedMesh");
  const key = name + ":" + getSetting("obj-tess");
  if (meshCache[key]) return meshCache[key];
  if (meshPending !== key) {
    meshPending = key;
    fetchJSON(`/api/mesh?name=${name}&tessellation=${getSetting("obj-tess")}`).then((m) => {
      meshCache[key] = meshBuffers(m); meshPending = null; store.requestDraw();
    }).catch((e) => { meshPending = null; showError(`mesh: ${e.message}`); });
  }
  return null;
}

export const meshReady = () => currentMesh() !== null;
