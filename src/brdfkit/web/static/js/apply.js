// Applying a state (the URL, a saved view file, window.brdfkit.setState): every bad part is
// shown on the page as an error, never dropped silently; the rest is still applied.

import * as store from "./store.js";
import { showError } from "./dom.js";
import { validated } from "./brdfs.js";
import { restoreFiles } from "./files.js";
import { addPanel, clearPanels } from "./panels.js";
import { setSetting } from "./settings.js";
import { urlToState } from "./urlstate.js";
import { VIEWS, showView } from "./layout.js";

// apply a state object; every bad part is reported on the page, the rest still applied
export async function applyState(st, origin) {
  if (st === null || typeof st !== "object" || Array.isArray(st)) throw new Error(`${origin}: expected a JSON object`);
  if (st.files !== undefined) await restoreFiles(st.files, origin);  // before the panels that use them
  const entries = [];
  if (st.model !== undefined && st.model !== null) entries.push({ model: st.model, params: st.params || {}, visible: st.visible !== false });
  if (st.compare !== undefined) {
    if (!Array.isArray(st.compare)) showError(`${origin}: compare must be a list of {"model", "params"}`);
    else for (const c of st.compare) {
      if (typeof c === "string") entries.push({ model: c, params: {}, visible: true });
      else if (c && typeof c === "object") entries.push({ model: c.model, params: c.params || {}, visible: c.visible !== false });
      else showError(`${origin}: bad compare entry ${JSON.stringify(c)}`);
    }
  }
  const good = [];
  for (const e of entries) {
    try {
      await validated(e.model, e.params);
      good.push(e);
    } catch (err) { showError(`${origin}: ${err.message}`); }
  }
  if (good.length) {
    clearPanels();
    for (const e of good) { const p = addPanel(e.model, e.params); p.setVisible(e.visible); }
  }
  const view = st.view === undefined ? {} : st.view;
  if (view === null || typeof view !== "object" || Array.isArray(view)) showError(`${origin}: view must be a JSON object`);
  else for (const [k, v] of Object.entries(store.get("defaults"))) if (!(k in view)) setSetting(k, v);  // the state is the whole view
  for (const [k, v] of Object.entries(view || {})) {
    try { setSetting(k, v); } catch (err) { showError(`${origin}: ${err.message}`); }
  }
  if (st.panes !== undefined) {
    if (!Array.isArray(st.panes) || st.panes.length !== 2 || st.panes.some((v) => !VIEWS.includes(v))) {
      showError(`${origin}: panes must be two of ${VIEWS.join(", ")}`);
    } else { showView(st.panes[0], 0); showView(st.panes[1], 1); }
  }
  if (st.orbit && typeof st.orbit === "object") {
    store.update("orbit", (orbit) => {
      for (const k of ["lobe3d", "object"]) {
        const o = st.orbit[k];
        if (!o) continue;
        for (const f of ["yaw", "pitch", "zoom"]) if (typeof o[f] === "number" && isFinite(o[f])) orbit[k][f] = o[f];
      }
    });
  }
  store.changed();
}

// a URL query (the page's own, or one given by a script) -> the state, errors shown on the page
export async function loadURL(search) {
  let st = null;
  try { st = urlToState(search); } catch (e) { showError(e); }
  if (st && !st.model) { showError("URL: missing 'model' (the first BRDF's name)"); st.model = undefined; }
  if (st) await applyState(st, "URL");
}
