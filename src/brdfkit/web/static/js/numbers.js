// Pure numbers: formatting, slider mappings, colour encoding and the page's geometry.
// The functions with a Python twin are pinned to it by tests/test_web_js_twins.py
// (many inputs, 1e-6 relative): srgbEncode / srgbToLinear (brdfkit.render.image),
// fromHalfDiff (brdfkit.geometry.from_rusinkiewicz), effectiveParams (the alpha rule of
// the microfacet-style models' parameters), eyeToMap (brdfkit.render.ibl.eye_to_map).

export const DEG = Math.PI / 180;
export const STEPS = 1000;          // slider positions
export const BACKGROUND = 0.06;     // linear grey behind the spheres
export const COLORS = ["#d9480f", "#1c7ed6", "#2b8a3e", "#ae3ec9", "#f08c00", "#0c8599", "#c2255c", "#5c940d"];

/** A number for the page: 4 significant digits, exponent form outside [1e-3, 1e5). */
export function fmt(x) {
  if (x === null || x === undefined || !isFinite(x)) return String(x);
  const a = Math.abs(x);
  if (a !== 0 && (a < 1e-3 || a >= 1e5)) return x.toExponential(3);
  return String(+x.toPrecision(4));
}

// IEC 61966-2-1 sRGB transfer functions (Python twin: brdfkit.render.image.srgb_encode).
export const srgbToLinear = (c) => (c <= 0.04045 ? c / 12.92 : Math.pow((c + 0.055) / 1.055, 2.4));
export const srgbEncode = (c) => (c <= 0.0031308 ? 12.92 * c : 1.055 * Math.pow(c, 1 / 2.4) - 0.055);

/** The unit vector at polar angle t and azimuth p (radians), z up. */
export const sph = (t, p) => [Math.sin(t) * Math.cos(p), Math.sin(t) * Math.sin(p), Math.cos(t)];

/** A list of [x, y, z] as a flat Float32Array. */
export function flat3(list) {
  const a = new Float32Array(3 * list.length);
  list.forEach((v, k) => { a[3 * k] = v[0]; a[3 * k + 1] = v[1]; a[3 * k + 2] = v[2]; });
  return a;
}

// A slider position t in [0, 1] <-> a parameter value, linear or logarithmic,
// respecting open bounds; the end points map exactly to closed bounds.
export function sliderMap(p) {
  const lo = p.min === null || p.min === undefined ? 0 : p.min;
  let hi = p.max;
  if (hi === null || hi === undefined) {
    const d = Array.isArray(p.default) ? Math.max(...p.default) : p.default;
    hi = Math.max(lo + 1, (d || 1) * 100);
  }
  const eps = (hi - lo) * 1e-3;
  const loEff = p.open_lo ? lo + eps : lo;
  const hiEff = p.open_hi ? hi - eps : hi;
  if (p.log_scale && hiEff > 0) {
    const a = loEff > 0 ? loEff : Math.max(hiEff * 1e-5, 1e-6);
    const la = Math.log(a), lb = Math.log(hiEff);
    return {
      lo, hi,
      toValue: (t) => (t <= 0 ? loEff : t >= 1 ? hiEff : Math.exp(la + t * (lb - la))),
      toSlider: (v) => (v <= a ? 0 : Math.min(1, (Math.log(v) - la) / (lb - la))),
      clamp: (v) => Math.min(hiEff, Math.max(loEff, v)),
    };
  }
  return {
    lo, hi,
    toValue: (t) => loEff + t * (hiEff - loEff),
    toSlider: (v) => Math.min(1, Math.max(0, (v - loEff) / (hiEff - loEff))),
    clamp: (v) => Math.min(hiEff, Math.max(loEff, v)),
  };
}

/** Defaults filled in, the microfacet-style alpha / alpha_x / alpha_y rule applied
 * (alpha given: both axes take it; else alpha is alpha_x when the axes agree, null when not). */
export function effectiveParams(info, given) {
  const v = {};
  for (const p of info.params) v[p.name] = p.default;
  for (const [k, x] of Object.entries(given || {})) {
    if (!(k in v)) throw new Error(`${info.name}: unknown parameter '${k}'`);
    v[k] = x;
  }
  if ("alpha" in v && "alpha_x" in v && "alpha_y" in v) {
    if (given && given.alpha !== undefined && given.alpha !== null) {
      v.alpha_x = v.alpha_y = given.alpha;
    } else {
      v.alpha = v.alpha_x === v.alpha_y ? v.alpha_x : null;
    }
  }
  return v;
}

/** Rusinkiewicz (1998) half/difference angles (θh, θd, φd; φh = 0) -> [wi, wo], as the SLICE shader
 * (Python twin: brdfkit.geometry.from_rusinkiewicz). */
export function fromHalfDiff(th, td, pd) {
  const h = [Math.sin(th), 0, Math.cos(th)];
  const bx = [Math.cos(th), 0, -Math.sin(th)];
  const d = [Math.sin(td) * Math.cos(pd), Math.sin(td) * Math.sin(pd), Math.cos(td)];
  const wi = [d[0] * bx[0] + d[2] * h[0], d[1], d[0] * bx[2] + d[2] * h[2]];
  const hw = h[0] * wi[0] + h[2] * wi[2];
  const wo = [2 * hw * h[0] - wi[0], -wi[1], 2 * hw * h[2] - wi[2]];
  return [wi, wo];
}

/** Column-major 4x4 product a·b. */
export function mat4Mul(a, b) {
  const o = new Float32Array(16);
  for (let c = 0; c < 4; c++) for (let r = 0; r < 4; r++) {
    let s = 0; for (let k = 0; k < 4; k++) s += a[k * 4 + r] * b[c * 4 + k]; o[c * 4 + r] = s;
  }
  return o;
}

/** The lit object's camera for an orbit {yaw, pitch, zoom} (degrees) and a w x h image:
 * modelview, projection (column-major 4x4) and the normal matrix (column-major 3x3). */
export function objectMatrices(o, w, h) {
  const cy = Math.cos(o.yaw * DEG), sy = Math.sin(o.yaw * DEG), cp = Math.cos(o.pitch * DEG), sp = Math.sin(o.pitch * DEG);
  const ry = new Float32Array([cy, 0, -sy, 0, 0, 1, 0, 0, sy, 0, cy, 0, 0, 0, 0, 1]);
  const rx = new Float32Array([1, 0, 0, 0, 0, cp, sp, 0, 0, -sp, cp, 0, 0, 0, 0, 1]);
  const dist = 3.4 / o.zoom;
  const tr = new Float32Array([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, -dist, 1]);
  const mv = mat4Mul(tr, mat4Mul(rx, ry));
  const f = 1 / Math.tan(17.5 * DEG), near = 0.1, far = 50, asp = w / h;
  const proj = new Float32Array([f / asp, 0, 0, 0, 0, f, 0, 0, 0, 0, (far + near) / (near - far), -1, 0, 0, 2 * far * near / (near - far), 0]);
  const nm = new Float32Array([mv[0], mv[1], mv[2], mv[4], mv[5], mv[6], mv[8], mv[9], mv[10]]); // a rotation: its own inverse transpose
  return { mv, proj, nm };
}

/** Eye -> environment map, column-major 3x3: the map's rotation after the inverse of the modelview's
 * (R, column-major 3x3, a rotation; W2M row-major), as brdfkit.render.ibl.eye_to_map. */
export function eyeToMap(R, W2M) {
  const e2m = new Float32Array(9);  // e2m[c*3+r] = Σ_k W2M[r][k] · (R^T)[k][c]
  for (let r = 0; r < 3; r++) for (let c = 0; c < 3; c++) {
    let sum = 0;
    for (let k = 0; k < 3; k++) sum += W2M[r * 3 + k] * R[k * 3 + c];  // (R^T)[k][c] = R[c][k] = R_colmajor[k*3 + c]
    e2m[c * 3 + r] = sum;
  }
  return e2m;
}
