// Requests to the page's own server (nothing is fetched from outside): an answer's
// {"error"} becomes an Error with that one line.

export async function fetchText(url) {
  const r = await fetch(url);
  const t = await r.text();
  if (!r.ok) { let m = t; try { m = JSON.parse(t).error; } catch (e) { /* plain text */ } throw new Error(m); }
  return t;
}

export async function fetchJSON(url, opts) {
  const r = await fetch(url, opts);
  const t = await r.text();
  let body;
  try { body = JSON.parse(t); } catch (e) { throw new Error(`${url}: not JSON (${r.status})`); }
  if (!r.ok) throw new Error(body.error || r.statusText);
  return body;
}
