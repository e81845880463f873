// The page's state as a JSON-able object (window.brdfkit.state(), the saved view) and as the URL:
// ?model=NAME&p=JSON&compare=JSON&view=JSON[&hide=1][&files=JSON] (SPEC.md, "The explorer page").
// Reading a URL throws a one-line Error naming the bad part; ./apply.js shows it on the page.

import * as store from "./store.js";
import { allSettings } from "./settings.js";
import { stateFiles } from "./files.js";

/** {model, params, visible, compare: [{model, params, visible}], panes, view, orbit[, files]}. */
export function getState() {
  const list = store.get("panels").filter((p) => p.model);
  const first = list[0];
  const st = {
    model: first ? first.model : null,
    params: first ? first.params() : {},
    visible: first ? first.visible : true,
    compare: list.slice(1).map((p) => ({ model: p.model, params: p.params(), visible: p.visible })),
    panes: store.get("panes").slice(),
    view: allSettings(),
    orbit: JSON.parse(JSON.stringify(store.get("orbit"))),
  };
  const files = stateFiles(list.map((p) => p.model));
  if (files.length) st.files = files;
  return st;
}

/** The query string of a state (view settings at their defaults left out). */
export function stateToURL(st) {
  const q = new URLSearchParams();
  q.set("model", st.model);
  q.set("p", JSON.stringify(st.params));
  if (st.visible === false) q.set("hide", "1");
  if (st.compare.length) q.set("compare", JSON.stringify(st.compare));
  if (st.files) q.set("files", JSON.stringify(st.files));
  const defaults = store.get("defaults");
  const view = {};
  for (const [k, v] of Object.entries(st.view)) if (v !== defaults[k]) view[k] = v;
  view.panes = st.panes;
  view.orbit = st.orbit;
  q.set("view", JSON.stringify(view));
  return "?" + q.toString();
}

function parseJSONParam(text, what) {
  try { return JSON.parse(text); } catch (e) { throw new Error(`${what}: not valid JSON (${e.message})`); }
}

/** A URL query -> a state object (throws with a one-line message naming the bad part). */
export function urlToState(search) {
  const q = new URLSearchParams(search);
  const allowed = new Set(["model", "p", "compare", "view", "hide", "files"]);
  for (const k of q.keys()) if (!allowed.has(k)) throw new Error(`URL: unknown parameter '${k}'; allowed: model, p, compare, view, files`);
  const st = { model: q.get("model"), params: {}, compare: [], view: {}, visible: q.get("hide") !== "1" };
  if (q.has("p")) st.params = parseJSONParam(q.get("p"), "URL p");
  if (q.has("files")) st.files = parseJSONParam(q.get("files"), "URL files");
  const c = q.get("compare");
  if (c) {
    if (c.trim().startsWith("[")) st.compare = parseJSONParam(c, "URL compare");
    else st.compare = c.split(",").filter((s) => s).map((m) => ({ model: m, params: {} }));
  }
  if (q.has("view")) {
    const v = parseJSONParam(q.get("view"), "URL view");
    if (v === null || typeof v !== "object" || Array.isArray(v)) throw new Error("URL view: must be a JSON object");
    if (v.panes) { st.panes = v.panes; delete v.panes; }
    if (v.orbit) { st.orbit = v.orbit; delete v.orbit; }
    st.view = v;
  }
  return st;
}

let urlTimer = null;

/** Write the state into the address bar, at most every 150 ms. */
export function updateURL() {
  if (urlTimer) return;
  urlTimer = setTimeout(() => {
    urlTimer = null;
    try { history.replaceState(null, "", stateToURL(getState())); } catch (e) { /* replaceState throttled */ }
  }, 150);
}

/** Write the state into the address bar now; -> location.search. */
export function flushURL() {
  if (urlTimer) { clearTimeout(urlTimer); urlTimer = null; }
  history.replaceState(null, "", stateToURL(getState()));
  return location.search;
}
