// DOM helpers and the page's error list (bad URL values, bad files, failed uploads: never silent).

export const $ = (sel, root) => (root || document).querySelector(sel);
export const $$ = (sel, root) => Array.from((root || document).querySelectorAll(sel));

export function el(tag, attrs, ...kids) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) {
    if (k === "class") e.className = v;
    else if (k === "text") e.textContent = v;
    else e.setAttribute(k, v);
  }
  for (const k of kids) e.append(k);
  return e;
}

/** The canvas of a view (index.html's `.view[data-view=NAME]`), wherever the view is shown. */
export const canvasOf = (name) => $(`.view[data-view="${name}"] canvas`);

export function setStatus(text, isError) {
  const s = $("#status");
  s.textContent = text;
  s.classList.toggle("error", !!isError);
}

const errorList = [];

/** Show one line of `msg` (an Error or text) in the page's error box, with a dismiss button. */
export function showError(msg) {
  const text = String(msg && msg.message || msg).split("\n")[0];
  errorList.push(text);
  const row = el("div", { class: "error-row" }, el("span", { text }));
  const x = el("button", { type: "button", title: "dismiss", text: "×" });
  x.addEventListener("click", () => row.remove());
  row.append(x);
  $("#errors").append(row);
}

export const errors = () => errorList.slice();
export function clearErrors() { $("#errors").textContent = ""; }

/** Save `blob` as `filename` through a temporary link. */
export function download(filename, blob) {
  const a = el("a", { href: URL.createObjectURL(blob), download: filename });
  document.body.append(a);
  a.click();
  setTimeout(() => { URL.revokeObjectURL(a.href); a.remove(); }, 1000);
}
